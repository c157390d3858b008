"""int8 versions of an exported model directory's ONNX files (``export-nemo --int8``,
``export-whisper --int8``), beside the fp32 ones and named as onnx-asr names them
(``encoder-model.int8.onnx``); the ``quantization`` key picks them.

Dynamic quantization (onnxruntime's quantizer): the weights of the matrix products become int8,
activations are quantized as each product runs, so no calibration audio is needed. Only MatMul is
quantized: the matrix products hold most of these models' weights (a conformer's feed-forward and
attention layers, Whisper's blocks), and the decoders' LSTM and embeddings stay exact. Products
inside a control-flow node's branches are quantized too (optimum's merged Whisper decoder).
bench/asr.py measures what it gains and what it changes.
"""

import logging
import os
from pathlib import Path
from typing import List

from speech_event.recognizers.onnx.directory import INT8_SUFFIXES

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


def quantize_directory(directory: Path) -> List[Path]:
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
            quantize_dynamic(
                model,
                partial,
                op_types_to_quantize=["MatMul"],
                weight_type=QuantType.QInt8,
                # optimum's merged Whisper decoder keeps its every product by a weight inside its If
                # node's two branches (with and without the cache), which the quantizer leaves
                # alone unless told to go into them
                extra_options={"EnableSubgraph": True},
            )
            os.replace(partial, target)
            written.append(target)
    finally:
        logging.getLogger().removeFilter(advice)
    return written


def quantize_and_say(directory: Path) -> None:
    """An exporter's --int8: quantize ``directory`` and say each file written."""
    for written in quantize_directory(directory):
        print(f"wrote {written} (int8: set quantization int8 to use it)")
