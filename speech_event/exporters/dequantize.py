"""A quantized ONNX graph in QDQ form as a float one: every weight dequantized once, as its
quantization defines it, and every activation's QuantizeLinear -> DequantizeLinear pair made the
Clip to the range that pair can hold, without its rounding.

Why: onnxruntime fuses a QDQ graph's pairs into integer kernels that it picks by CPU, and those
differ: AVX2's saturates 8-bit weights (quantize.py), and rounding the activations turns the
smallest difference into a step. Smart Turn v3.2's int8 file (turns/smart_turn.py) moved by 0.11 on
a reading, and by 0.4 on a command, when the samples moved by one part in a million. The float
graph moves by a few parts in a million there, which is as much as float additions in another order
(another CPU's kernels) move it.

Why the Clip: the quantized model's function is its weights on the int8 grid and its activations
held within their calibrated ranges. Removing the pairs outright undid the ranges as well, and
Smart Turn then heard slt's "stop" with its pause as 0.06 complete, where the int8 file hears 0.96
and the graph with the Clip 0.94.
"""

from typing import TYPE_CHECKING, List, Sequence, Tuple

import numpy as np

if TYPE_CHECKING:  # onnx comes with the smart-turn, export and pull extras, imported where used
    import onnx

QUANTIZE = "QuantizeLinear"
DEQUANTIZE = "DequantizeLinear"


def float_graph(model: "onnx.ModelProto") -> "onnx.ModelProto":
    """``model`` in float (the module's docstring); ValueError for a graph this cannot convert: a
    quantized value read by anything but its DequantizeLinear, a quantized graph output, an
    activation quantized along an axis, block quantization, or a dequantized value neither a weight
    nor an activation's pair."""
    from onnx import helper, numpy_helper

    graph = model.graph
    weights = {tensor.name: tensor for tensor in graph.initializer}
    quantized = {node.output[0]: node for node in graph.node if node.op_type == QUANTIZE}

    def constants(names: Sequence[str]) -> List[np.ndarray]:
        return [numpy_helper.to_array(weights[name]) for name in names if name]

    added: List[onnx.TensorProto] = []  # dequantized weights and the Clips' bounds
    kept: List[onnx.NodeProto] = []
    for node in graph.node:
        if node.op_type == DEQUANTIZE and node.input[0] in weights:
            value = _dequantized(node, constants(node.input))
            added.append(numpy_helper.from_array(value, node.output[0]))
        elif node.op_type == DEQUANTIZE and node.input[0] in quantized:
            pair = quantized[node.input[0]]
            low, high = _held(pair, constants(pair.input[1:]))
            bounds = [f"{node.output[0]}_low", f"{node.output[0]}_high"]
            added += [numpy_helper.from_array(low, bounds[0]), numpy_helper.from_array(high, bounds[1])]
            kept.append(helper.make_node("Clip", [pair.input[0], *bounds], [node.output[0]], name=node.name))
        elif node.op_type == DEQUANTIZE:
            raise ValueError(f"{node.name}: dequantizes {node.input[0]}, neither a weight nor an activation")
        elif node.op_type != QUANTIZE:
            kept.append(node)
    for node in kept:
        if any(name in quantized for name in node.input):
            raise ValueError(f"{node.name} ({node.op_type}) reads a quantized value itself")
    outputs = {output.name for output in graph.output}
    if outputs & set(quantized):
        raise ValueError(f"graph outputs {sorted(outputs & set(quantized))} are quantized")
    read = {name for node in kept for name in node.input} | outputs
    float_weights = [tensor for tensor in [*graph.initializer, *added] if tensor.name in read]
    rebuilt = helper.make_graph(kept, graph.name, graph.input, graph.output, float_weights)
    return helper.make_model(rebuilt, opset_imports=model.opset_import, ir_version=model.ir_version)


def _held(pair: "onnx.NodeProto", inputs: List[np.ndarray]) -> Tuple[np.ndarray, np.ndarray]:
    """The range a QuantizeLinear -> DequantizeLinear pair holds: scale x (the integer type's
    least and greatest - zero point), float32 scalars."""
    if len(inputs) < 2 or inputs[0].size != 1:
        raise ValueError(f"{pair.name}: an activation quantized without one scale and zero point")
    scale, zero = inputs[0].astype(np.float32).reshape(()), inputs[1].reshape(())
    limits = np.iinfo(zero.dtype)
    least, greatest = (np.float32(int(limit) - int(zero)) * scale for limit in (limits.min, limits.max))
    return np.asarray(least, np.float32), np.asarray(greatest, np.float32)


def _dequantized(node: "onnx.NodeProto", inputs: List[np.ndarray]) -> np.ndarray:
    """DequantizeLinear's (x - zero_point) * scale of constant inputs, per tensor or along its axis."""
    attributes = {attribute.name: attribute for attribute in node.attribute}
    if "block_size" in attributes and attributes["block_size"].i:
        raise ValueError(f"{node.name}: block quantization is not undone here")
    values, scale = inputs[0], inputs[1].astype(np.float32)
    zero = inputs[2] if len(inputs) > 2 else np.zeros(scale.shape, values.dtype)
    if scale.size > 1:  # one scale along the axis: shaped to broadcast over the others
        axis = attributes["axis"].i if "axis" in attributes else 1
        shape = [1] * values.ndim
        shape[axis] = -1
        scale, zero = scale.reshape(shape), zero.reshape(shape)
    difference = values.astype(np.int64) - zero.astype(np.int64)
    return (difference.astype(np.float32) * scale).astype(np.float32)
