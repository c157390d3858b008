"""The Whisper graphs built from numpy weights (speech_event/exporters/whisper_graphs.py), on the
small random Whisper of fixtures/ct2_whisper_model.py: the token embedding stored once, a decoder
holding it twice (as torch.onnx writes it) brought to once with the same logits, the
decoder's cache giving what one pass over all the tokens gives, and the encoder's attention by
onnxruntime's MultiHeadAttention computing whisper's."""

from dataclasses import replace
from pathlib import Path
from typing import Dict, List

import numpy as np
import onnx
import onnxruntime
import pytest
from onnx import TensorProto, helper, numpy_helper

from fixtures.ct2_whisper_model import LAYERS, VOCABULARY, WIDTH, write_whisper_directory
from speech_event.exporters.faster_whisper import read_faster_whisper
from speech_event.exporters.quantize import quantize_directory
from speech_event.exporters.whisper_graphs import (
    HALF_EMBEDDING,
    TIED_EMBEDDING,
    _Graph,
    decoder_graph,
    encoder_graph,
    share_transposed_embedding,
)
from speech_event.exporters.whisper_weights import WhisperWeights
from speech_event.recognizers.whisper.features import whisper_log_mel
from speech_event.recognizers.whisper.model import cross_names

EMBEDDING_ELEMENTS = len(VOCABULARY) * WIDTH
TOKENS = [54, 61, 3, 30, 44, 7]  # sot, no timestamps, then text tokens


@pytest.fixture(scope="module")
def weights(tmp_path_factory: pytest.TempPathFactory) -> WhisperWeights:
    directory = write_whisper_directory(tmp_path_factory.mktemp("faster-whisper"))
    return read_faster_whisper(directory, {}).weights


@pytest.fixture(scope="module")
def float16_weights(weights: WhisperWeights) -> WhisperWeights:
    """The weights with a token embedding float16 holds exactly, as a float16 model.bin's is."""
    return replace(weights, embedding=weights.embedding.astype(np.float16).astype(np.float32))


@pytest.fixture(scope="module")
def cross(weights: WhisperWeights) -> Dict[str, np.ndarray]:
    """The encoder's outputs for a second of a chirp."""
    time = np.arange(16000) / 16000
    mel = whisper_log_mel(np.sin(2 * np.pi * (200 + 600 * time) * time).astype(np.float32), 80)
    session = onnxruntime.InferenceSession(encoder_graph(weights).SerializeToString())
    outputs = session.run(None, {"mel": mel[None]})
    return dict(zip(cross_names(LAYERS), outputs))


def _embeddings(model: onnx.ModelProto) -> List[str]:
    """The initializers as large as the token embedding."""
    return [
        tensor.name for tensor in model.graph.initializer if int(np.prod(tensor.dims)) == EMBEDDING_ELEMENTS
    ]


def _logits(model: onnx.ModelProto, cross: Dict[str, np.ndarray], steps: List[List[int]]) -> np.ndarray:
    """The logits of each step's tokens, the cache carried from step to step, all steps' rows."""
    session = onnxruntime.InferenceSession(model.SerializeToString())
    cache = np.zeros((LAYERS, 1, 2, 0, WIDTH // 2), np.float32)
    self_k = self_v = cache
    rows = []
    for tokens in steps:
        logits, self_k, self_v = session.run(
            None, {"tokens": np.array([tokens], np.int64), "self_k": self_k, "self_v": self_v, **cross}
        )
        rows.append(logits[0])
    return np.concatenate(rows)


def _untied(model: onnx.ModelProto) -> onnx.ModelProto:
    """The decoder as torch.onnx writes it: the embedding gathered by rows from a copy of its own."""
    untied = onnx.ModelProto()
    untied.CopyFrom(model)
    graph = untied.graph
    table = next(tensor for tensor in graph.initializer if tensor.name == TIED_EMBEDDING)
    graph.initializer.append(
        numpy_helper.from_array(numpy_helper.to_array(table).T.copy(), "embedding.weight")
    )
    lookup = [
        index
        for index, node in enumerate(graph.node)
        if node.input[:1] == [TIED_EMBEDDING] and node.op_type == "Gather"
    ]
    assert len(lookup) == 1
    output = graph.node[lookup[0] + 1].output[0]  # the lookup's Transpose
    del graph.node[lookup[0] : lookup[0] + 2]
    graph.node.insert(lookup[0], helper.make_node("Gather", ["embedding.weight", "tokens"], [output]))
    return untied


def test_the_decoder_stores_the_token_embedding_once_and_the_logits_read_it(weights: WhisperWeights) -> None:
    model = decoder_graph(weights)
    assert _embeddings(model) == [TIED_EMBEDDING]
    readers = sorted(node.op_type for node in model.graph.node if TIED_EMBEDDING in node.input)
    assert readers == ["Gather", "MatMul"]
    logits = next(node for node in model.graph.node if node.output[0] == "logits")
    assert (logits.op_type, logits.input[1]) == ("MatMul", TIED_EMBEDDING)


def test_a_token_embedding_float16_holds_is_gathered_from_a_float16_copy_with_the_same_logits(
    float16_weights: WhisperWeights, cross: Dict[str, np.ndarray]
) -> None:
    """onnxruntime frees the float32 table once prepacked for the logits when no lookup reads it."""
    model = decoder_graph(float16_weights)
    assert _embeddings(model) == [TIED_EMBEDDING, HALF_EMBEDDING]
    assert [node.op_type for node in model.graph.node if TIED_EMBEDDING in node.input] == ["MatMul"]
    lookup = next(node for node in model.graph.node if HALF_EMBEDDING in node.input)
    cast = next(node for node in model.graph.node if lookup.output[0] in node.input)
    assert (lookup.op_type, cast.op_type) == ("Gather", "Cast")
    float32_lookup = onnx.ModelProto()
    float32_lookup.CopyFrom(model)
    graph = float32_lookup.graph
    graph.node.remove(next(node for node in graph.node if node.op_type == "Cast"))
    next(node for node in graph.node if HALF_EMBEDDING in node.input).CopyFrom(
        helper.make_node("Gather", [TIED_EMBEDDING, "tokens"], [cast.output[0]], axis=1)
    )
    np.testing.assert_array_equal(_logits(model, cross, [TOKENS]), _logits(float32_lookup, cross, [TOKENS]))


def test_a_decoder_holding_the_embedding_twice_gets_it_once_with_the_same_logits(
    weights: WhisperWeights, cross: Dict[str, np.ndarray]
) -> None:
    untied = _untied(decoder_graph(weights))
    assert _embeddings(untied) == [TIED_EMBEDDING, "embedding.weight"]
    before = _logits(untied, cross, [TOKENS])
    assert share_transposed_embedding(untied) == EMBEDDING_ELEMENTS * 4
    assert _embeddings(untied) == [TIED_EMBEDDING]
    onnx.checker.check_model(untied)
    np.testing.assert_array_equal(_logits(untied, cross, [TOKENS]), before)


def test_a_decoder_without_a_second_copy_is_left_as_it_is(weights: WhisperWeights) -> None:
    model = decoder_graph(weights)
    before = model.SerializeToString()
    assert share_transposed_embedding(model) == 0
    assert model.SerializeToString() == before


def test_decoding_a_token_a_step_with_the_cache_gives_the_logits_of_one_pass(
    weights: WhisperWeights, cross: Dict[str, np.ndarray]
) -> None:
    model = decoder_graph(weights)
    whole = _logits(model, cross, [TOKENS])
    np.testing.assert_allclose(
        _logits(model, cross, [TOKENS[:2], *([token] for token in TOKENS[2:])]), whole, atol=1e-5
    )
    np.testing.assert_allclose(_logits(model, cross, [TOKENS[:3], TOKENS[3:]]), whole, atol=1e-5)
    # and the later tokens change no earlier position's logits (the mask is causal)
    np.testing.assert_allclose(_logits(model, cross, [TOKENS[:3]]), whole[:3], atol=1e-5)


def test_the_encoder_gives_each_decoder_block_its_cross_keys_and_values(cross: Dict[str, np.ndarray]) -> None:
    assert {name: array.shape for name, array in cross.items()} == {
        "cross_k_0": (1, 2, 8, 1500),
        "cross_v_0": (1, 2, 1500, 8),
        "cross_k_1": (1, 2, 8, 1500),
        "cross_v_1": (1, 2, 1500, 8),
    }


def test_the_written_files_pass_onnxs_checker(weights: WhisperWeights, tmp_path: Path) -> None:
    for name, model in (("encoder.onnx", encoder_graph(weights)), ("decoder.onnx", decoder_graph(weights))):
        onnx.save(model, str(tmp_path / name))
        onnx.checker.check_model(str(tmp_path / name), full_check=True)


@pytest.mark.parametrize("embedding", ["weights", "float16_weights"])
def test_the_int8_decoder_holds_the_token_embedding_once_in_int8_and_gathers_its_rows_exactly(
    embedding: str, request: pytest.FixtureRequest, cross: Dict[str, np.ndarray], tmp_path: Path
) -> None:
    """The int8 file's lookup reads the int8 table the logits' product reads, and dequantizes the
    columns it took, each with its own scale and zero point: the same logits as a lookup of the whole
    table dequantized, without its fp32 copy (nor the float16 one the fp32 file's lookup reads where
    float16 holds the table)."""
    onnx.save(decoder_graph(request.getfixturevalue(embedding)), str(tmp_path / "decoder.onnx"))
    (int8_path,) = quantize_directory(tmp_path)
    assert sorted(path.name for path in tmp_path.iterdir()) == ["decoder.int8.onnx", "decoder.onnx"]
    int8 = onnx.load(str(int8_path))
    table = TIED_EMBEDDING + "_quantized"
    assert _embeddings(int8) == [table]
    tensors = {tensor.name: numpy_helper.to_array(tensor) for tensor in int8.graph.initializer}
    assert tensors[table].dtype == np.int8  # 7 bits, a scale a column: exporters/quantize.py
    assert tensors[table].min() >= -64 and tensors[table].max() <= 64  # 255 x 64 x 2 < 2 ** 15
    scale, zero_point = tensors[TIED_EMBEDDING + "_scale"], tensors[TIED_EMBEDDING + "_zero_point"]
    assert scale.shape == zero_point.shape == (tensors[table].shape[1],)
    readers = sorted(node.op_type for node in int8.graph.node if table in node.input)
    assert readers == ["Gather", "MatMulInteger"]
    # the reference: the whole table dequantized as DequantizeLinear does, gathered in fp32
    reference = onnx.ModelProto()
    reference.CopyFrom(int8)
    graph = reference.graph
    dequantized = (tensors[table].astype(np.int32) - zero_point.astype(np.int32)).astype(np.float32) * scale
    graph.initializer.append(numpy_helper.from_array(dequantized, "dequantized"))
    lookup = next(node for node in graph.node if node.op_type == "Gather" and node.input[0] == table)
    rows = lookup.output[0].removesuffix(".int8")
    for node in [
        node for node in graph.node if node.output[0].startswith(rows + ".") or node.output[0] == rows
    ]:
        if node is not lookup:
            graph.node.remove(node)
    lookup.input[0], lookup.output[0] = "dequantized", rows
    np.testing.assert_array_equal(_logits(int8, cross, [TOKENS]), _logits(reference, cross, [TOKENS]))


def test_the_encoders_attention_is_onnxruntimes_multi_head_attention_and_computes_whispers(
    weights: WhisperWeights,
) -> None:
    """One MultiHeadAttention a block and no Softmax of 1500 x 1500 scores; on a 30 s window of
    random positions, what whisper's attention computes: softmax(q k^T / sqrt(head width)) v by
    head, merged, projected."""
    ops = [node.op_type for node in encoder_graph(weights).graph.node]
    assert (ops.count("MultiHeadAttention"), ops.count("Softmax")) == (len(weights.encoder_blocks), 0)
    block, heads = weights.encoder_blocks[0], weights.encoder_heads
    g = _Graph(WIDTH, weights.layer_norm_epsilon)
    g.op("Identity", g.self_attention("x", block.qkv, block.attention_out, heads, "attention"), name="y")
    positions = int(weights.audio_positions.shape[0])
    model = g.model(
        "attention",
        [("x", TensorProto.FLOAT, [1, positions, WIDTH])],
        [("y", TensorProto.FLOAT, [1, positions, WIDTH])],
    )
    x = np.random.default_rng(0).standard_normal((positions, WIDTH)).astype(np.float32)
    (y,) = onnxruntime.InferenceSession(model.SerializeToString()).run(None, {"x": x[None]})

    q, k, v = np.split(x @ block.qkv.weight.T + block.qkv.bias, 3, axis=-1)
    width = WIDTH // heads
    attended = []
    for head in range(heads):
        part = slice(head * width, (head + 1) * width)
        scores = q[:, part] @ k[:, part].T / np.sqrt(width)
        probabilities = np.exp(scores - scores.max(axis=-1, keepdims=True))
        attended.append(probabilities / probabilities.sum(axis=-1, keepdims=True) @ v[:, part])
    expected = np.concatenate(attended, axis=-1) @ block.attention_out.weight.T + block.attention_out.bias
    np.testing.assert_allclose(y[0], expected, rtol=1e-4, atol=1e-5)
