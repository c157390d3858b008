"""A QDQ graph as float (speech_event/exporters/dequantize.py), on a graph built here: an activation
quantized to uint8 and a matrix of int8 weights with a scale a column, as Smart Turn's file holds
them. The float graph computes clip(x) @ dequantized weights, with no rounding anywhere."""

from typing import List

import numpy as np
import onnx
import onnxruntime
import pytest
from onnx import TensorProto, helper, numpy_helper

from speech_event.exporters.dequantize import float_graph

SCALE, ZERO = np.float32(0.02), np.uint8(128)  # the activation holds -2.56 to 2.54
WEIGHTS = np.array([[-127, 3], [64, -1], [5, 127]], np.int8)
COLUMN_SCALES = np.array([0.5, 0.25], np.float32)


def _qdq_product(reader: str = "DequantizeLinear", output: str = "y") -> onnx.ModelProto:
    constants = [
        numpy_helper.from_array(np.array(SCALE), "scale"),
        numpy_helper.from_array(np.array(ZERO), "zero"),
        numpy_helper.from_array(WEIGHTS, "w_q"),
        numpy_helper.from_array(COLUMN_SCALES, "w_scale"),
        numpy_helper.from_array(np.zeros(2, np.int8), "w_zero"),
    ]
    nodes = [
        helper.make_node("QuantizeLinear", ["x", "scale", "zero"], ["x_q"], name="quantize"),
        helper.make_node(reader, ["x_q", "scale", "zero"], ["x_dq"], name="activation"),
        helper.make_node("DequantizeLinear", ["w_q", "w_scale", "w_zero"], ["w"], axis=1, name="weights"),
        helper.make_node("MatMul", ["x_dq", "w"], ["y"], name="product"),
    ]
    outputs = [
        helper.make_tensor_value_info(output, TensorProto.FLOAT if output == "y" else TensorProto.UINT8, None)
    ]
    graph = helper.make_graph(
        nodes, "qdq", [helper.make_tensor_value_info("x", TensorProto.FLOAT, [None, 3])], outputs, constants
    )
    return helper.make_model(graph, opset_imports=[helper.make_opsetid("", 18)])


def _run(model: onnx.ModelProto, x: np.ndarray) -> np.ndarray:
    session = onnxruntime.InferenceSession(model.SerializeToString(), providers=["CPUExecutionProvider"])
    outputs: List[np.ndarray] = session.run(None, {"x": x})
    return outputs[0]


def test_the_float_graph_clips_the_activation_to_its_range_and_reads_the_weights_dequantized() -> None:
    converted = float_graph(_qdq_product())
    assert [node.op_type for node in converted.graph.node] == ["Clip", "MatMul"]
    x = np.array(
        [[0.013, -1.0, 2.0], [-3.0, 0.5, 9.0]], np.float32
    )  # 0.013 between steps; -3 and 9 out of range
    weights = WEIGHTS.astype(np.float32) * COLUMN_SCALES
    expected = np.clip(x, -2.56, 2.54) @ weights
    np.testing.assert_allclose(_run(converted, x), expected, rtol=1e-6, atol=1e-6)
    # the quantized graph rounds 0.013 to 0.02: the float one does not
    assert not np.allclose(_run(_qdq_product(), x), expected, rtol=1e-6, atol=1e-6)


def test_a_quantized_value_read_by_another_operator_or_given_out_is_refused() -> None:
    with pytest.raises(ValueError, match=r"activation \(Identity\) reads a quantized value itself"):
        float_graph(_qdq_product(reader="Identity"))
    with pytest.raises(ValueError, match=r"graph outputs \['x_q'\] are quantized"):
        float_graph(_qdq_product(output="x_q"))
