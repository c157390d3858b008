"""The two Whisper model directories the engine reads: speech-event export-whisper's (config.json
with our keys, tokens.txt, encoder.onnx, decoder.onnx) and Hugging Face optimum's (transformers'
config.json, generation_config.json, vocab.json, added_tokens.json; encoder_model.onnx and
decoder_model_merged.onnx at the root, as speech-event pull writes them, or in ``onnx/``, as the
onnx-community repositories hold them)."""

from pathlib import Path
from typing import List, Tuple

from speech_event.recognizers.onnx.directory import Runtime
from speech_event.recognizers.whisper.manifest import (
    MANIFEST_FILE,
    TOKENS_FILE,
    WhisperManifest,
    load_tokens,
    load_whisper_manifest,
)
from speech_event.recognizers.whisper.model import WhisperModel, WhisperOnnx
from speech_event.recognizers.whisper.optimum_layout import (
    is_optimum_directory,
    load_optimum_manifest,
    load_optimum_pieces,
)
from speech_event.recognizers.whisper.optimum_model import ENCODER_FILE, OptimumWhisperModel

ONNX_FOLDER = "onnx"  # where a Hugging Face repository keeps its ONNX files


def onnx_files_folder(directory: Path) -> Path:
    """Where the ONNX files of an optimum export are: ``onnx/`` when the root has no encoder file."""
    folder = directory / ONNX_FOLDER
    if not any(directory.glob(f"{ENCODER_FILE[: -len('.onnx')]}*.onnx")) and folder.is_dir():
        return folder
    return directory


def load_whisper_directory(
    directory: Path, runtime: Runtime
) -> Tuple[WhisperManifest, List[bytes], WhisperOnnx]:
    """The manifest, each token's bytes and the ONNX model of either layout in ``directory``."""
    if is_optimum_directory(directory) and not (directory / TOKENS_FILE).is_file():
        manifest = load_optimum_manifest(directory)
        pieces = load_optimum_pieces(directory, manifest.vocabulary_size)
        return manifest, pieces, OptimumWhisperModel(onnx_files_folder(directory), runtime)
    manifest = load_whisper_manifest(directory / MANIFEST_FILE)
    return manifest, load_tokens(directory / TOKENS_FILE), WhisperModel(directory, runtime)
