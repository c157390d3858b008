"""int8 versions of an exported model directory's ONNX files (``export-nemo --int8``,
``export-whisper --int8``), beside the fp32 ones and named as onnx-asr names them
(``encoder-model.int8.onnx``); the ``quantization`` key picks them.

Dynamic quantization (onnxruntime's quantizer): the weights of the matrix products become int8,
activations are quantized as each product runs, so no calibration audio is needed. Only MatMul is
quantized: the matrix products hold most of these models' weights (a conformer's feed-forward and
attention layers, Whisper's blocks), and the decoders' LSTM and embeddings stay exact, but for a
table a product reads too (below). Products inside a control-flow node's branches are quantized too
(optimum's merged Whisper decoder).
bench/figures/asr.py measures what it gains and what it changes.

The weights are signed 7-bit numbers with a scale per output column (Int8Scheme): the same
results on every x86-64 CPU, at int8's speed. onnxruntime picks its int8 kernels by CPU, and AVX2's
kernel for unsigned activations by signed weights adds pairs of products in 16 bits, which saturate
with 8-bit weights (255 x 127 x 2 > 32767) but not with 7-bit ones (255 x 64 x 2 < 32767): measured
under qemu as a Haswell (bench/figures/int8_cpus.py), a random Whisper's logits moved 5x as far from fp32
as on an AVX-512 VNNI CPU with onnxruntime's default (8-bit, one scale a matrix), 27x with 8-bit
per-column scales, and exactly as far with 7-bit ones. Unsigned weights do not saturate either,
but take a slower kernel: trained tiny.en decoded 1.36x as long on this CPU.

A table that is both a product's weight and gathered from (Whisper's tied token embedding: the
logits' weight and the tokens' lookup) is gathered from its int8 version too, then dequantized, so
the file holds it once, in int8: the fp32 table was 80 of tiny.en's 109 MB int8 decoder, and 106 of
base's 156 (bench/figures/whisper_peer.py measures the memory it saves). An fp32 file's lookup of an exact
float16 copy of the table (exporters/whisper_graphs.py says why) is made a lookup of the table
itself first, so the int8 file holds neither copy.
"""

import logging
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Iterator, List

import numpy as np

from speech_event.exporters.graph_files import (
    EXTERNAL_DATA_SUFFIX,
    has_weights_beside,
    remove_graph,
    save_graph,
)
from speech_event.recognizers.onnx.directory import INT8_SUFFIXES

if TYPE_CHECKING:  # onnx comes with the export and pull extras, imported where it is used
    import onnx

INT8_SUFFIX = INT8_SUFFIXES[0]
INT8_HELP = "also write each ONNX file's int8 version (*.int8.onnx), which quantization int8 runs"


# onnxruntime's quantizer says this on the root logger for every file: its pre-processing (shape
# inference, graph optimisation) helps static quantization's calibration; dynamic MatMul
# quantization has none, and the advice would only be noise on every export --int8.
_PREPROCESSING_ADVICE = "Please consider to run pre-processing before quantization"


class _WithoutPreprocessingAdvice(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        return not record.getMessage().startswith(_PREPROCESSING_ADVICE)


def int8_name(name: str) -> str:
    """``encoder-model.onnx`` -> ``encoder-model.int8.onnx``."""
    return name[: -len(".onnx")] + INT8_SUFFIX


@dataclass(frozen=True)
class Int8Scheme:
    """How the products' weights are stored in 8 bits (the module's docstring says why the default)."""

    unsigned: bool = False
    per_channel: bool = True  # a scale and zero point per output column, not one for the whole matrix
    seven_bits: bool = True  # onnxruntime's reduce_range: signed weights in [-64, 64]


# What export --int8 wrote before 2026-11-28, onnxruntime's default: AVX2's kernel saturates on it.
SIGNED_PER_TENSOR = Int8Scheme(unsigned=False, per_channel=False, seven_bits=False)


def quantize_directory(directory: Path, scheme: Int8Scheme = Int8Scheme()) -> List[Path]:
    """Write the int8 version of every fp32 ONNX file in ``directory``; the files written. Each is
    written under a temporary name first, so a file of that name is never half-written."""
    from onnxruntime.quantization import QuantType, quantize_dynamic

    written = []
    advice = _WithoutPreprocessingAdvice()
    logging.getLogger().addFilter(advice)
    try:
        for model in sorted(directory.glob("*.onnx")):
            if model.name.endswith(INT8_SUFFIXES):
                continue
            target = model.with_name(int8_name(model.name))
            partial = target.with_name(target.name + ".partial")
            source = _with_float32_lookups(model, target.with_name(target.name + ".source"))
            try:
                quantize_dynamic(
                    source,
                    partial,
                    op_types_to_quantize=["MatMul"],
                    weight_type=QuantType.QUInt8 if scheme.unsigned else QuantType.QInt8,
                    per_channel=scheme.per_channel,
                    reduce_range=scheme.seven_bits,
                    # optimum's merged Whisper decoder keeps its every product by a weight inside its
                    # If node's two branches (with and without the cache), which the quantizer leaves
                    # alone unless told to go into them
                    extra_options={"EnableSubgraph": True},
                )
            finally:
                if source != model:
                    remove_graph(source)
            _finish(partial, target, has_weights_beside(model))
            written.append(target)
    finally:
        logging.getLogger().removeFilter(advice)
    return written


def _read(graph: "onnx.GraphProto") -> Iterator[str]:
    """The names the graph's nodes read, those of its control-flow nodes' branches included (a
    branch may read the main graph's initializers)."""
    for node in graph.node:
        yield from node.input
        for attribute in node.attribute:
            for branch in [attribute.g] if attribute.HasField("g") else attribute.graphs:
                yield from _read(branch)


def lookups_from_float32_tables(model: "onnx.ModelProto") -> List[str]:
    """Make every Gather of a float16 table whose rows are then cast to float32 read the float32
    table of the same values instead, without the cast, and drop the float16 table when nothing
    else reads it; the float16 tables so replaced. The quantizer then sees one table, which the
    int8 file gathers from (gather_from_int8_tables)."""
    from onnx import TensorProto, numpy_helper

    graph = model.graph
    # only the float16 tables, and the float32 ones of their shape, are read as arrays: a model's
    # every weight would be a copy of the whole model (Whisper large's fp32 decoder: 3.2 GB)
    halves = {
        tensor.name: tensor
        for tensor in graph.initializer
        if tensor.data_type == TensorProto.FLOAT16 and len(tensor.dims) > 1
    }
    to_float = [TensorProto.FLOAT]
    replaced = []
    for gather in [node for node in graph.node if node.op_type == "Gather" and node.input[0] in halves]:
        readers = [node for node in graph.node if gather.output[0] in node.input]
        if len(readers) != 1 or readers[0].op_type != "Cast":
            continue
        if [attribute.i for attribute in readers[0].attribute if attribute.name == "to"] != to_float:
            continue
        half = numpy_helper.to_array(halves[gather.input[0]])
        table = next(
            (
                tensor.name
                for tensor in graph.initializer
                if tensor.data_type == TensorProto.FLOAT
                and tuple(tensor.dims) == half.shape
                and np.array_equal(numpy_helper.to_array(tensor), half)
            ),
            None,
        )
        if table is None:
            continue
        replaced.append(gather.input[0])
        gather.input[0], gather.output[0] = table, readers[0].output[0]
        graph.node.remove(readers[0])
    unread = set(replaced) - set(_read(graph))
    for tensor in [tensor for tensor in graph.initializer if tensor.name in unread]:
        graph.initializer.remove(tensor)
    return sorted(replaced)


def _with_float32_lookups(path: Path, rewritten: Path) -> Path:
    """``path``, or where lookups_from_float32_tables changes it, that model written to ``rewritten``
    (its weights beside it)."""
    import onnx

    model = onnx.load(str(path))
    if not lookups_from_float32_tables(model):
        return path
    save_graph(model, rewritten)
    return rewritten


def gather_from_int8_tables(model: "onnx.ModelProto") -> List[str]:
    """Make every Gather of the main graph that reads a table the quantizer also wrote in int8
    (``T_quantized``, ``T_scale``, ``T_zero_point``) read the int8 table and dequantize the rows it
    took, and drop the fp32 table when nothing else reads it; the tables now gathered in int8.
    Dequantizing the rows taken gives exactly the rows of the dequantized table.

    One scale for the whole table: the rows dequantize with it whatever axis they were taken along.
    A scale per channel (a product's output column) fits a lookup along the channels, the table's
    last axis (Whisper's tied embedding, stored transposed): each column taken is dequantized with
    its own scale and zero point, gathered by the same indices."""
    from onnx import TensorProto, helper

    graph = model.graph
    shapes = {tensor.name: list(tensor.dims) for tensor in graph.initializer}
    changed = []
    for index in reversed(range(len(graph.node))):  # inserting after a node leaves those before in place
        node = graph.node[index]
        table = node.input[0] if node.op_type == "Gather" else ""
        quantized = [table + "_quantized", table + "_scale", table + "_zero_point"]
        if table not in shapes or not set(quantized) <= set(shapes):
            continue
        axis = next((attribute.i for attribute in node.attribute if attribute.name == "axis"), 0)
        along_channels = [axis % len(shapes[table])] == [len(shapes[table]) - 1]
        per_channel = shapes[quantized[1]] == shapes[table][-1:] and along_channels
        if shapes[quantized[1]] and not per_channel:
            continue
        rows, indices = node.output[0], node.input[1]
        node.input[0] = quantized[0]
        node.output[0] = rows + ".int8"
        if per_channel:
            # (rows - zero point) * scale as DequantizeLinear computes it: the difference of two
            # 8-bit integers is exact in float32, so the product is the same float
            dequantize = [
                helper.make_node("Gather", [quantized[1], indices], [rows + ".scale"]),
                helper.make_node("Gather", [quantized[2], indices], [rows + ".zero_point"]),
                helper.make_node("Cast", [rows + ".int8"], [rows + ".int8.float"], to=TensorProto.FLOAT),
                helper.make_node(
                    "Cast", [rows + ".zero_point"], [rows + ".zero_point.float"], to=TensorProto.FLOAT
                ),
                helper.make_node(
                    "Sub", [rows + ".int8.float", rows + ".zero_point.float"], [rows + ".centred"]
                ),
                helper.make_node("Mul", [rows + ".centred", rows + ".scale"], [rows]),
            ]
        else:
            dequantize = [helper.make_node("DequantizeLinear", [rows + ".int8", *quantized[1:]], [rows])]
        for offset, added in enumerate(dequantize, start=1):
            graph.node.insert(index + offset, added)
        changed.append(table)
    unread = set(changed) - set(_read(graph))
    for tensor in [tensor for tensor in graph.initializer if tensor.name in unread]:
        graph.initializer.remove(tensor)
    return sorted(changed)


def _finish(partial: Path, target: Path, weights_beside: bool) -> None:
    """The quantizer's ``partial`` file made ``target``: its tables gathered from in int8
    (gather_from_int8_tables), its weights beside it where the fp32 file's are (what that saves
    while loading: exporters/graph_files.py). The graph is renamed last, whole."""
    import onnx

    model = onnx.load(str(partial))
    gather_from_int8_tables(model)
    if weights_beside:
        save_graph(model, partial, target.name + EXTERNAL_DATA_SUFFIX)
    else:
        onnx.save(model, str(partial))
    os.replace(partial, target)


def quantize_and_say(directory: Path) -> None:
    """An exporter's --int8: quantize ``directory`` and say each file written."""
    for written in quantize_directory(directory):
        print(f"wrote {written} (int8: set quantization int8 to use it)")
