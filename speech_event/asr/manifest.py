"""config.json of a model directory: the feature settings, from the model's own preprocessor config.

Keys are NeMo's preprocessor names (sample_rate, window_size, window_stride, n_fft, features,
normalize, preemph) plus max_symbols_per_step; onnx-asr's names (features_size,
max_tokens_per_step) are written too, so the same directory loads in onnx-asr.
"""

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict

from speech_event.asr.errors import ModelError
from speech_event.asr.features import FeatureSettings

MANIFEST_FILE = "config.json"


@dataclass(frozen=True)
class Manifest:
    features: FeatureSettings
    max_symbols_per_step: int = 10


def manifest_json(manifest: Manifest) -> Dict[str, Any]:
    settings = manifest.features
    return {
        "model_type": "nemo-conformer-rnnt",
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


def load_manifest(path: Path) -> Manifest:
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
        settings = FeatureSettings(
            sample_rate=int(document["sample_rate"]),
            window_seconds=float(document["window_size"]),
            stride_seconds=float(document["window_stride"]),
            n_fft=int(document["n_fft"]),
            mel_bands=int(document["features"]),
            preemphasis=float(document.get("preemph", 0.97)),
            normalize=str(document.get("normalize", "per_feature")),
        )
        return Manifest(settings, int(document.get("max_symbols_per_step", 10)))
    except OSError as problem:
        raise ModelError(f"{path}: cannot read the model's config: {problem.strerror}") from None
    except (ValueError, KeyError, TypeError) as problem:
        raise ModelError(
            f"{path}: not a usable model config ({problem!r}); it needs sample_rate, window_size, "
            "window_stride, n_fft and features, as in NeMo's preprocessor config"
        ) from None
