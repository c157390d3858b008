"""Whisper's encoder and decoder as the ONNX graphs of speech-event export-whisper's directory
(recognizers/whisper/model.py says their tensors), built with onnx.helper from numpy weights: no
torch. What openai-whisper computes (its model.py), float32:

- encoder: conv1 (kernel 3, padding 1) and GELU, conv2 (kernel 3, stride 2, padding 1) and GELU,
  the sinusoidal positions added, pre-LayerNorm blocks (self-attention, MLP with GELU), a final
  LayerNorm; then each decoder block's cross-attention keys and values of that audio, split by
  head, the keys transposed;
- decoder: the token embedding plus learned positions from the cache's length on, pre-LayerNorm
  blocks (causal self-attention over the cache and the new tokens, cross-attention, MLP), a final
  LayerNorm, and the logits: the output by the token embedding, transposed (tied weights).

The decoder's attention scales the queries and keys by head width ** -0.25 each, as whisper does;
here the scale is folded into their projections' weights. The encoder's self-attention is one
onnxruntime MultiHeadAttention node (com.microsoft), which scales by head width ** -0.5 itself: its
CPU kernel never holds a head's 1500 x 1500 scores twice, as MatMul, Softmax, MatMul do, and since
onnxruntime 1.19 it attends in blocks (flash attention) and holds none. That was most of what an
int8 tiny.en held at its peak besides its weights (bench/figures/whisper_peer.py measures it). GELU is
erf's (whisper's nn.GELU), written as torch.onnx writes it, a pattern onnxruntime fuses into one
kernel.

The token embedding is one initializer, stored transposed [width, vocabulary]: the logits' MatMul
reads it as a weight (so the int8 version quantizes it), and the embedding of the tokens gathers
its columns. ``share_transposed_embedding`` does the same to a decoder that holds the embedding
twice (torch.onnx folds the transpose the logits read into a second copy). Where float16 holds the
table exactly (a float16 model.bin's weights: every faster-whisper model published), the lookup
gathers from a float16 copy instead and casts the columns it took back, the same values: onnxruntime
prepacks the logits' weight into a copy of its own and frees the table only when no other node
reads it, so a lookup of the float32 table kept it twice in memory (tiny.en's decoder loads in 161
MiB instead of 215). The int8 quantizer gathers from the table again (exporters/quantize.py).

The graphs are saved with their weights in a file beside them (exporters/graph_files.py).
"""

from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper

from speech_event.exporters.whisper_weights import Dense, Norm, WhisperWeights
from speech_event.recognizers.whisper.model import cross_names

OPSET = 17
# onnxruntime's own operators: MultiHeadAttention, right on a CPU since onnxruntime 1.16 (1.15's
# kernel gives other outputs for separate queries, keys and values: measured), hence pyproject's floor
MICROSOFT_DOMAIN = "com.microsoft"
# Every onnxruntime since 1.13 loads IR version 8 with opset 17; onnx.helper would write its own, newer one.
IR_VERSION = 8
TIED_EMBEDDING = "decoder.token_embedding.transposed"
HALF_EMBEDDING = TIED_EMBEDDING + ".float16"


Shape = Sequence[Union[int, str]]


class _Graph:
    """Nodes and initializers being gathered, each value given a fresh name."""

    def __init__(self, width: int, epsilon: float) -> None:
        self.width = width
        self.epsilon = epsilon
        self.nodes: List[onnx.NodeProto] = []
        self.initializers: List[onnx.TensorProto] = []
        # the types of values onnx's shape inference cannot know (the outputs of onnxruntime's own
        # operators), which onnxruntime's quantizer needs of every product's input
        self.value_info: List[onnx.ValueInfoProto] = []
        self._count = 0

    def weight(self, name: str, values: np.ndarray) -> str:
        self.initializers.append(numpy_helper.from_array(np.ascontiguousarray(values, np.float32), name))
        return name

    def constant(self, values: object) -> str:
        """A small constant (a shape, an axis, a scalar), named after its place among the initializers."""
        name = f"constant_{len(self.initializers)}"
        self.initializers.append(numpy_helper.from_array(np.asarray(values), name))
        return name

    def op(self, op_type: str, *inputs: str, name: str = "", **attributes: Any) -> str:
        """Add a node of one output, named ``name`` (a graph output) or afresh; the output's name."""
        return self.op_outputs(op_type, list(inputs), [name] if name else 1, **attributes)[0]

    def op_outputs(
        self, op_type: str, inputs: List[str], outputs: Union[List[str], int], **attributes: Any
    ) -> List[str]:
        """Add a node of the outputs named, or of that many named afresh; their names."""
        self._count += 1
        if isinstance(outputs, int):
            outputs = [f"{op_type.lower()}_{self._count}_{index}" for index in range(outputs)]
        self.nodes.append(helper.make_node(op_type, inputs, outputs, **attributes))
        return outputs

    def linear(self, x: str, dense: Dense, name: str, scale: Optional[np.ndarray] = None) -> str:
        """x @ weight.T + bias; ``scale`` multiplies each output column (folded into the weights)."""
        factor = np.ones(dense.weight.shape[0], np.float32) if scale is None else scale
        y = self.op("MatMul", x, self.weight(f"{name}.weight", dense.weight.T * factor))
        return self.op("Add", y, self.weight(f"{name}.bias", dense.bias * factor))

    def norm(self, x: str, norm: Norm, name: str) -> str:
        gamma, beta = self.weight(f"{name}.gamma", norm.gamma), self.weight(f"{name}.beta", norm.beta)
        return self.op("LayerNormalization", x, gamma, beta, axis=-1, epsilon=self.epsilon)

    def gelu(self, x: str) -> str:
        """x * (1 + erf(x / sqrt 2)) / 2, as torch.onnx writes nn.GELU."""
        erf = self.op("Erf", self.op("Div", x, self.constant(np.float32(np.sqrt(2.0)))))
        doubled = self.op("Mul", x, self.op("Add", erf, self.constant(np.float32(1.0))))
        return self.op("Mul", doubled, self.constant(np.float32(0.5)))

    def heads(self, x: str, heads: int) -> str:
        """[1, positions, width] -> [1, heads, positions, head width]."""
        split = self.op("Reshape", x, self.constant(np.array([1, -1, heads, self.width // heads], np.int64)))
        return self.op("Transpose", split, perm=[0, 2, 1, 3])

    def projected_heads(
        self, x: str, dense: Dense, name: str, heads: int, parts: int, scaled: int
    ) -> List[str]:
        """x by a projection of ``parts`` fused outputs (q, k, v; or k, v), each split by head; the
        first ``scaled`` (queries and keys) by head width ** -0.25, folded into the weights."""
        scale = (self.width // heads) ** -0.25
        factor = np.repeat([scale] * scaled + [1.0] * (parts - scaled), self.width).astype(np.float32)
        fused = self.linear(x, dense, name, factor)
        pieces = self.op_outputs("Split", [fused], parts, axis=-1) if parts > 1 else [fused]
        return [self.heads(piece, heads) for piece in pieces]

    def transposed(self, x: str) -> str:
        """[1, heads, positions, head width] -> [1, heads, head width, positions]."""
        return self.op("Transpose", x, perm=[0, 1, 3, 2])

    def attend(self, q: str, k_transposed: str, v: str, mask: Optional[str], out: Dense, name: str) -> str:
        """Attention of the heads, merged back to [1, positions, width] and projected by ``out``."""
        scores = self.op("MatMul", q, k_transposed)
        if mask is not None:
            scores = self.op("Add", scores, mask)
        attended = self.op("MatMul", self.op("Softmax", scores, axis=-1), v)
        together = self.op("Transpose", attended, perm=[0, 2, 1, 3])
        merged = self.op("Reshape", together, self.constant(np.array([1, 0, -1], np.int64)))
        return self.linear(merged, out, name)

    def self_attention(self, x: str, qkv: Dense, out: Dense, heads: int, name: str) -> str:
        """Attention of ``x`` [1, positions, width] to itself by onnxruntime's MultiHeadAttention, of
        the fused projection's queries, keys and values, projected by ``out``."""
        q, k, v = self.op_outputs("Split", [self.linear(x, qkv, f"{name}.qkv")], 3, axis=-1)
        (attended,) = self.op_outputs(
            "MultiHeadAttention", [q, k, v], 1, domain=MICROSOFT_DOMAIN, num_heads=heads
        )
        self.value_info.append(
            helper.make_tensor_value_info(attended, TensorProto.FLOAT, [1, "positions", self.width])
        )
        return self.linear(attended, out, f"{name}.out")

    def mlp(self, x: str, norm: Norm, first: Dense, second: Dense, name: str) -> str:
        """x plus the MLP (Linear, GELU, Linear) of its norm."""
        hidden = self.gelu(self.linear(self.norm(x, norm, f"{name}.norm"), first, f"{name}.in"))
        return self.op("Add", x, self.linear(hidden, second, f"{name}.out"))

    def model(
        self, name: str, inputs: List[Tuple[str, int, Shape]], outputs: List[Tuple[str, int, Shape]]
    ) -> onnx.ModelProto:
        """The graph gathered, its inputs and outputs (name, element type, shape); onnxruntime's
        operator set among its imports when a node uses it."""
        graph = helper.make_graph(
            self.nodes,
            name,
            [helper.make_tensor_value_info(*value) for value in inputs],
            [helper.make_tensor_value_info(*value) for value in outputs],
            self.initializers,
            value_info=self.value_info,
        )
        imports = [helper.make_opsetid("", OPSET)]
        if any(node.domain == MICROSOFT_DOMAIN for node in self.nodes):
            imports.append(helper.make_opsetid(MICROSOFT_DOMAIN, 1))
        return helper.make_model(graph, opset_imports=imports, ir_version=IR_VERSION)


def _cross_shapes(names: List[str], heads: int, head_width: int, audio: int) -> List[Tuple[str, int, Shape]]:
    """cross_k_i [1, heads, head width, audio positions], cross_v_i [1, heads, audio positions, head
    width]."""
    return [
        (
            name,
            TensorProto.FLOAT,
            [1, heads, head_width, audio] if name.startswith("cross_k") else [1, heads, audio, head_width],
        )
        for name in names
    ]


def encoder_graph(weights: WhisperWeights) -> onnx.ModelProto:
    """encoder.onnx: ``mel`` [1, mel bands, 2 x audio positions] -> each decoder block's
    ``cross_k_i`` and ``cross_v_i``."""
    g = _Graph(weights.width, weights.layer_norm_epsilon)
    x = "mel"
    for index, (conv, stride) in enumerate([(weights.conv1, 1), (weights.conv2, 2)], start=1):
        name = f"encoder.conv{index}"
        convolved = g.op(
            "Conv",
            x,
            g.weight(f"{name}.weight", conv.weight),
            g.weight(f"{name}.bias", conv.bias),
            pads=[1, 1],
            strides=[stride],
        )
        x = g.gelu(convolved)
    x = g.op(
        "Add", g.op("Transpose", x, perm=[0, 2, 1]), g.weight("encoder.positions", weights.audio_positions)
    )
    heads = weights.encoder_heads
    for index, block in enumerate(weights.encoder_blocks):
        name = f"encoder.blocks.{index}"
        h = g.norm(x, block.attention_norm, f"{name}.attention.norm")
        x = g.op("Add", x, g.self_attention(h, block.qkv, block.attention_out, heads, f"{name}.attention"))
        x = g.mlp(x, block.mlp_norm, block.mlp_in, block.mlp_out, f"{name}.mlp")
    audio = g.norm(x, weights.encoder_norm, "encoder.norm")
    names = cross_names(len(weights.decoder_blocks))
    for index, decoder_block in enumerate(weights.decoder_blocks):
        k, v = g.projected_heads(
            audio,
            decoder_block.cross_kv,
            f"decoder.blocks.{index}.cross.kv",
            weights.decoder_heads,
            parts=2,
            scaled=1,
        )
        g.op("Transpose", k, perm=[0, 1, 3, 2], name=names[2 * index])
        g.op("Identity", v, name=names[2 * index + 1])
    positions = int(weights.audio_positions.shape[0])
    return g.model(
        "whisper_encoder",
        [("mel", TensorProto.FLOAT, [1, weights.mel_bands, 2 * positions])],
        _cross_shapes(names, weights.decoder_heads, weights.width // weights.decoder_heads, positions),
    )


def tied_lookup(table: str, tokens: str, output: str, float16: bool = False) -> List[onnx.NodeProto]:
    """The nodes that embed ``tokens`` [1, n] from the transposed embedding ``table`` [width,
    vocabulary] into ``output`` [1, n, width]: its columns gathered ([width, 1, n]), cast to float32
    when the table is ``float16``, then moved."""
    columns = f"{output}.columns"
    gathered = f"{columns}.float16" if float16 else columns
    cast = [helper.make_node("Cast", [gathered], [columns], to=TensorProto.FLOAT)] if float16 else []
    return [
        helper.make_node("Gather", [table, tokens], [gathered], axis=1),
        *cast,
        helper.make_node("Transpose", [columns], [output], perm=[1, 2, 0]),
    ]


def _embedding_lookup(g: _Graph, transposed: np.ndarray, table: str) -> None:
    """Embed the graph's ``tokens`` into ``embedded`` from ``table``, the initializer holding
    ``transposed``, or from its float16 copy where that holds the same values (the module's
    docstring says why)."""
    half = transposed.astype(np.float16)
    if not np.array_equal(half, transposed):
        g.nodes.extend(tied_lookup(table, "tokens", "embedded"))
        return
    g.initializers.append(numpy_helper.from_array(half, HALF_EMBEDDING))
    g.nodes.extend(tied_lookup(HALF_EMBEDDING, "tokens", "embedded", float16=True))


def decoder_graph(weights: WhisperWeights) -> onnx.ModelProto:
    """decoder.onnx: ``tokens`` [1, n], the self-attention cache ``self_k``, ``self_v`` [layers, 1,
    heads, past, head width] and every ``cross_k_i``, ``cross_v_i`` -> ``logits`` [1, n, vocabulary]
    and the cache grown by the n tokens, ``new_self_k``, ``new_self_v``."""
    g = _Graph(weights.width, weights.layer_norm_epsilon)
    heads, layers = weights.decoder_heads, len(weights.decoder_blocks)
    zero, one = g.constant(np.array([0], np.int64)), g.constant(np.array([1], np.int64))
    past = g.op(
        "Slice",
        g.op("Shape", "self_k"),
        g.constant(np.array([3], np.int64)),
        g.constant(np.array([4], np.int64)),
    )
    count = g.op("Slice", g.op("Shape", "tokens"), one, g.constant(np.array([2], np.int64)))
    end = g.op("Squeeze", g.op("Add", past, count), zero)
    step = g.constant(np.array(1, np.int64))
    positions = g.op("Range", g.op("Squeeze", past, zero), end, step)  # [n]: past .. past + n - 1
    keys = g.op("Range", g.constant(np.array(0, np.int64)), end, step)  # [past + n]
    # causal: the token at position p sees the keys up to p
    future = g.op("Greater", g.op("Unsqueeze", keys, zero), g.op("Unsqueeze", positions, one))
    mask = g.op(
        "Where", future, g.constant(np.float32(-np.inf)), g.constant(np.float32(0.0))
    )  # [n, past + n]
    table = g.weight(TIED_EMBEDDING, weights.embedding.T)
    _embedding_lookup(g, weights.embedding.T, table)
    x = g.op(
        "Add", "embedded", g.op("Gather", g.weight("decoder.positions", weights.text_positions), positions)
    )
    cross = cross_names(layers)
    new_k: List[str] = []
    new_v: List[str] = []
    for index, block in enumerate(weights.decoder_blocks):
        name = f"decoder.blocks.{index}"
        layer = g.constant(np.array(index, np.int64))
        h = g.norm(x, block.attention_norm, f"{name}.attention.norm")
        q, k, v = g.projected_heads(h, block.qkv, f"{name}.attention.qkv", heads, parts=3, scaled=2)
        k = g.op("Concat", g.op("Gather", "self_k", layer), k, axis=2)
        v = g.op("Concat", g.op("Gather", "self_v", layer), v, axis=2)
        new_k.append(g.op("Unsqueeze", k, zero))
        new_v.append(g.op("Unsqueeze", v, zero))
        x = g.op(
            "Add", x, g.attend(q, g.transposed(k), v, mask, block.attention_out, f"{name}.attention.out")
        )
        h = g.norm(x, block.cross_norm, f"{name}.cross.norm")
        (query,) = g.projected_heads(h, block.cross_query, f"{name}.cross.query", heads, parts=1, scaled=1)
        x = g.op(
            "Add",
            x,
            g.attend(
                query, cross[2 * index], cross[2 * index + 1], None, block.cross_out, f"{name}.cross.out"
            ),
        )
        x = g.mlp(x, block.mlp_norm, block.mlp_in, block.mlp_out, f"{name}.mlp")
    g.op("MatMul", g.norm(x, weights.decoder_norm, "decoder.norm"), table, name="logits")
    g.op("Concat", *new_k, axis=0, name="new_self_k")
    g.op("Concat", *new_v, axis=0, name="new_self_v")
    head_width = weights.width // heads
    cache: Shape = [layers, 1, heads, "past", head_width]
    grown: Shape = [layers, 1, heads, "positions", head_width]
    return g.model(
        "whisper_decoder",
        [
            ("tokens", TensorProto.INT64, [1, "tokens"]),
            ("self_k", TensorProto.FLOAT, cache),
            ("self_v", TensorProto.FLOAT, cache),
            *_cross_shapes(cross, heads, head_width, int(weights.audio_positions.shape[0])),
        ],
        [
            ("logits", TensorProto.FLOAT, [1, "tokens", int(weights.embedding.shape[0])]),
            ("new_self_k", TensorProto.FLOAT, grown),
            ("new_self_v", TensorProto.FLOAT, grown),
        ],
    )


def _embeds_tokens(node: onnx.NodeProto, graph: onnx.GraphProto, matrices: Dict[str, np.ndarray]) -> bool:
    """Whether ``node`` is the embedding of the graph's tokens: a Gather of the rows of a matrix
    (an initializer) that nothing else reads."""
    return (
        node.op_type == "Gather"
        and list(node.input[1:]) == ["tokens"]
        and node.input[0] in matrices
        and all(attribute.i == 0 for attribute in node.attribute if attribute.name == "axis")
        and sum(list(other.input).count(node.input[0]) for other in graph.node) == 1
    )


def share_transposed_embedding(model: onnx.ModelProto) -> int:
    """Store the token embedding once in a decoder that holds it twice: the embedding [vocabulary,
    width] that a Gather reads the graph's ``tokens`` from, and its exact transpose (the logits'
    weight). The Gather becomes the tied lookup of the transposed copy and the embedding goes.
    Returns the bytes saved: 0 when the decoder has no such pair."""
    graph = model.graph
    matrices = {
        tensor.name: numpy_helper.to_array(tensor) for tensor in graph.initializer if len(tensor.dims) == 2
    }
    for position, node in enumerate(graph.node):
        if not _embeds_tokens(node, graph, matrices):
            continue
        transposed = matrices[node.input[0]].T
        twin = next(
            (
                name
                for name, matrix in matrices.items()
                if matrix.shape == transposed.shape and np.array_equal(matrix, transposed)
            ),
            None,
        )
        if twin is None:
            return 0
        embedding = node.input[0]
        lookup = tied_lookup(twin, "tokens", node.output[0])
        del graph.node[position]
        for offset, new in enumerate(lookup):
            graph.node.insert(position + offset, new)
        kept = [tensor for tensor in graph.initializer if tensor.name != embedding]
        del graph.initializer[:]
        graph.initializer.extend(kept)
        return int(transposed.nbytes)
    return 0
