"""``speech-event pull`` of a faster-whisper (CTranslate2) repository: the files downloaded into
huggingface_hub's cache converted into the Whisper engine's directory by export-whisper's converter
(exporters/faster_whisper.py), and with --int8 quantized (exporters/quantize.py).

The directory holds what export-whisper writes (encoder.onnx, decoder.onnx, tokens.txt, config.json);
with --int8 the int8 graphs instead of the fp32 ones, as every ``pull --int8`` directory holds only
int8 files. model.bin and the vocabulary stay in the cache only: the engine reads neither, and a
rerun converts again without downloading them again.

Converting needs the onnx package, which the ``pull`` extra installs; it, the language and the
repository's config.json are checked before model.bin is downloaded.
"""

from pathlib import Path

from speech_event.errors import ModelError
from speech_event.exporters.faster_whisper import export_faster_whisper, read_config
from speech_event.exporters.graph_files import remove_graph
from speech_event.exporters.quantize import quantize_directory
from speech_event.recognizers.onnx.directory import MANIFEST_FILE
from speech_event.recognizers.onnx.families import family_of
from speech_event.recognizers.whisper.manifest import TOKENS_FILE, WHISPER, load_tokens, load_whisper_manifest
from speech_event.recognizers.whisper.model import DECODER_FILE, ENCODER_FILE

ONNX_MISSING = (
    "pull converts a faster-whisper model to ONNX files with the onnx package: "
    "pip install 'speech-event[pull]' (or pip install onnx)"
)
NO_KINYARWANDA = (
    "Whisper has no Kinyarwanda language token, so a faster-whisper model serves english only (a "
    "fine-tune that uses another language's token for Kinyarwanda: download it, then speech-event "
    "export-whisper DIR OUT_DIR --language kinyarwanda=CODE)"
)


def check_convertible(config: Path, language: str) -> None:
    """Before model.bin is downloaded: ModelError when the model could not be converted here or
    would not serve ``language`` (config.json, downloaded, is not CTranslate2's Whisper config;
    onnx is not installed)."""
    if language != "english":
        raise ModelError(NO_KINYARWANDA)
    read_config(config)
    try:
        import onnx  # noqa: F401  (only to know it is there: the converter imports it when it writes)
    except ImportError:
        raise ModelError(ONNX_MISSING) from None


def convert(snapshot: Path, directory: Path, int8: bool) -> str:
    """Write the engine's directory for the faster-whisper model in ``snapshot`` to ``directory``
    (which must not exist); its family. ModelError says what the converter could not read."""
    export_faster_whisper(snapshot, directory, {})
    if int8:
        quantize_directory(directory)
        for graph in (ENCODER_FILE, DECODER_FILE):
            remove_graph(directory / graph)  # the fp32 graph and its weights
    # as the engine reads the directory
    load_whisper_manifest(directory / MANIFEST_FILE)
    load_tokens(directory / TOKENS_FILE)
    return family_of(directory, unrecorded=WHISPER)
