"""config.json of a model directory: what the exporter read from the model's own config.

Keys: the family (the robot's ``model``: conformer-transducer or parakeet), the decoding
(``model_type``, onnx-asr's names: nemo-conformer-rnnt, nemo-conformer-tdt, nemo-conformer-ctc),
the encoder's subsampling factor, TDT's durations, NeMo's preprocessor settings (sample_rate,
window_size, window_stride, n_fft, features, normalize, preemph) and max_symbols_per_step.
onnx-asr's names (features_size, max_tokens_per_step) are written too, so the same directory
loads in onnx-asr. A directory written before the family and decoding were recorded is a
conformer-transducer with RNN-T decoding. onnx-asr's own directories load as they are: what their
config.json (or a directory without one) does not record is derived (onnx_asr_layout.py).
"""

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Optional, Tuple

from speech_event.errors import ModelError
from speech_event.recognizers.nemo.features import FeatureSettings
from speech_event.recognizers.nemo.onnx_asr_layout import CTC as CTC
from speech_event.recognizers.nemo.onnx_asr_layout import RNNT as RNNT
from speech_event.recognizers.nemo.onnx_asr_layout import TDT as TDT
from speech_event.recognizers.nemo.onnx_asr_layout import completed, decoding_of
from speech_event.recognizers.onnx.directory import MANIFEST_FILE as MANIFEST_FILE
from speech_event.recognizers.onnx.families import register_family

DECODINGS = (RNNT, TDT, CTC)
CONFORMER_TRANSDUCER, PARAKEET = "conformer-transducer", "parakeet"
NEMO_FAMILIES = (CONFORMER_TRANSDUCER, PARAKEET)
# The family of a directory that does not record it (onnx-asr's): the decoding says
FAMILY_OF_DECODING = {RNNT: CONFORMER_TRANSDUCER, TDT: PARAKEET, CTC: PARAKEET}


@dataclass(frozen=True)
class Manifest:
    """What config.json of a NeMo model directory says: features, decoding, family, durations."""

    features: FeatureSettings
    max_symbols_per_step: int = 10
    decoding: str = RNNT
    family: str = CONFORMER_TRANSDUCER
    subsampling_factor: int = 4
    durations: Tuple[int, ...] = ()  # TDT only: the frames each duration output moves on


def manifest_json(manifest: Manifest) -> Dict[str, Any]:
    """The config.json document of ``manifest``, with onnx-asr's key names too."""
    settings = manifest.features
    document: Dict[str, Any] = {
        "model_type": manifest.decoding,
        "family": manifest.family,
        "subsampling_factor": manifest.subsampling_factor,
        "sample_rate": settings.sample_rate,
        "window_size": settings.window_seconds,
        "window_stride": settings.stride_seconds,
        "n_fft": settings.n_fft,
        "features": settings.mel_bands,
        "features_size": settings.mel_bands,
        "normalize": settings.normalize,
        "preemph": settings.preemphasis,
        "max_symbols_per_step": manifest.max_symbols_per_step,
        "max_tokens_per_step": manifest.max_symbols_per_step,
    }
    if manifest.decoding == TDT:
        document["durations"] = list(manifest.durations)
    return document


def _checked(manifest: Manifest) -> Manifest:
    if manifest.decoding not in DECODINGS:
        raise ValueError(f"model_type {manifest.decoding!r} is not one of {', '.join(DECODINGS)}")
    if manifest.family not in NEMO_FAMILIES:
        raise ValueError(f"family {manifest.family!r} is not one of {', '.join(NEMO_FAMILIES)}")
    if manifest.decoding == TDT and (not manifest.durations or min(manifest.durations) < 0):
        raise ValueError("a TDT model needs its durations (frames, 0 or more), e.g. [0, 1, 2, 3, 4]")
    if manifest.subsampling_factor < 1 or manifest.max_symbols_per_step < 1:
        raise ValueError("subsampling_factor and max_symbols_per_step must be at least 1")
    return manifest


def _document(path: Path) -> Dict[str, Any]:
    """config.json at ``path`` as a JSON object; {} when there is none (onnx-asr's may have none)."""
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        if path.parent.is_dir():
            return {}
        raise
    if not isinstance(document, dict):
        raise ValueError(f"{MANIFEST_FILE} is not a JSON object")
    return document


def load_manifest(path: Path) -> Manifest:
    """Read a model directory's config.json (``path``), deriving what an onnx-asr directory's does
    not record (onnx_asr_layout.py); ModelError says what is missing or wrong."""
    try:
        document = completed(_document(path), path.parent)
        decoding = str(document.get("model_type", RNNT))
        settings = FeatureSettings(
            sample_rate=int(document["sample_rate"]),
            window_seconds=float(document["window_size"]),
            stride_seconds=float(document["window_stride"]),
            n_fft=int(document["n_fft"]),
            mel_bands=int(document["features"]),
            preemphasis=float(document.get("preemph", 0.97)),
            normalize=str(document.get("normalize", "per_feature")),
        )
        return _checked(
            Manifest(
                settings,
                int(document.get("max_symbols_per_step", 10)),
                decoding,
                str(document.get("family", FAMILY_OF_DECODING.get(decoding, CONFORMER_TRANSDUCER))),
                int(document.get("subsampling_factor", 4)),
                tuple(int(duration) for duration in document.get("durations", ())),
            )
        )
    except OSError as problem:
        raise ModelError(f"{path}: cannot read the model's config: {problem.strerror}") from None
    except (ValueError, KeyError, TypeError) as problem:
        raise ModelError(
            f"{path}: not a usable model config ({problem!r}); it needs sample_rate, window_size, "
            "window_stride, n_fft and features, as in NeMo's preprocessor config, and names its "
            "model_type, family and (TDT) durations as speech-event export-nemo writes them"
        ) from None


def nemo_family_of(directory: Path, document: Dict[str, Any]) -> Optional[str]:
    """The family of the NeMo model in ``directory`` whose config.json (``document``) does not record
    it (onnx-asr's): its decoding's, read as load_manifest reads it but no further; None when the
    directory is no NeMo model's, or it cannot be told."""
    try:
        return FAMILY_OF_DECODING.get(decoding_of(document, directory))
    except (OSError, ValueError, ModelError):
        return None


register_family(nemo_family_of)
