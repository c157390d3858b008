"""An exported model directory: a directory, not the framework's own file, with its config.json
(what it records is each family's; the family itself: families.py); and which of its ONNX files an
engine runs (fp32 or int8)."""

from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Union

from speech_event.errors import ModelError

MANIFEST_FILE = "config.json"


def exported_directory(path: Union[str, Path], framework_suffix: str, export: str) -> Path:
    """``path`` as a model directory; a framework file (``framework_suffix``) gets how to export it
    (``export``: the command, with its extra)."""
    directory = Path(path)
    if directory.suffix == framework_suffix:
        raise ModelError(
            f"{directory} is a {framework_suffix} file, not an exported model directory: export it once with "
            f"'speech-event {export} {directory} OUT_DIR' (needs the 'export' extra), then give OUT_DIR"
        )
    if not directory.is_dir():
        raise ModelError(f"{directory}: no such model directory")
    return directory


# An int8 file's name after its fp32 file's stem: onnx-asr's (and our exporters') .int8, optimum's _int8.
INT8_SUFFIXES = (".int8.onnx", "_int8.onnx")


def int8_file(directory: Path, name: str) -> Optional[Path]:
    """The int8 version of ``name`` (``encoder-model.onnx``) in ``directory``, if there is one."""
    stem = name[: -len(".onnx")]
    return next(
        (path for path in (directory / (stem + suffix) for suffix in INT8_SUFFIXES) if path.is_file()), None
    )


@dataclass(frozen=True)
class Runtime:
    """How an engine runs its ONNX files: on CUDA or the CPU (the ``cuda`` key), and whether from
    their int8 versions (the ``quantization`` key)."""

    cuda: bool = False
    int8: bool = False

    def model_file(self, directory: Path, name: str) -> Path:
        """``name`` in ``directory``, or its int8 version: with int8, that one (ModelError if there
        is none); otherwise the fp32 file, or the int8 one when only that is there."""
        quantized = int8_file(directory, name)
        if self.int8:
            if quantized is None:
                raise ModelError(
                    f"{directory}: quantization is int8 but there is no int8 version of {name} "
                    f"({name[: -len('.onnx')]}.int8.onnx): export with --int8, pull with --int8, "
                    "or set quantization none"
                )
            return quantized
        fp32 = directory / name
        return quantized if quantized is not None and not fp32.is_file() else fp32


CPU_FP32 = Runtime()
