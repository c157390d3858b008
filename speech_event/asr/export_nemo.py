"""``speech-event export-nemo MODEL.nemo OUT_DIR``: a .nemo transducer to the directory the engine loads.

NeMo's own exporter writes the two ONNX files (``model.export("model.onnx")`` names them
encoder-model.onnx and decoder_joint-model.onnx); vocab.txt comes from the joint's vocabulary with
the blank last; config.json from the model's own preprocessor config and greedy decoding settings.
Needs nemo_toolkit (the ``export`` extra) on a workstation; never on the robot.
"""

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Sequence

from speech_event.asr.errors import ModelError
from speech_event.asr.features import FeatureSettings
from speech_event.asr.manifest import MANIFEST_FILE, Manifest, manifest_json

# Preprocessor settings our features implement, and the value NeMo uses when the config omits one.
_SUPPORTED = {"window": "hann", "log": True, "frame_splicing": 1, "mag_power": 2.0, "pad_to": 0}
_DEFAULTS = {"window": "hann", "log": True, "frame_splicing": 1, "mag_power": 2.0, "pad_to": 16}


def manifest_from_preprocessor(preprocessor: Mapping[str, Any], max_symbols: Optional[int]) -> Manifest:
    """Our manifest from NeMo's AudioToMelSpectrogramPreprocessor config, or why it cannot be."""
    for key, supported in _SUPPORTED.items():
        value = preprocessor.get(key, _DEFAULTS[key])
        # pad_to only pads the batch at training time; at inference any value gives the same frames.
        if key != "pad_to" and value != supported:
            raise ModelError(
                f"preprocessor {key} = {value!r} is not supported; the engine computes {key} = {supported!r}"
            )
    rate = int(preprocessor.get("sample_rate", 16000))
    window = float(preprocessor.get("window_size", 0.02))
    n_fft = preprocessor.get("n_fft") or 2 ** math.ceil(math.log2(window * rate))
    normalize = preprocessor.get("normalize", "per_feature")
    settings = FeatureSettings(
        sample_rate=rate,
        window_seconds=window,
        stride_seconds=float(preprocessor.get("window_stride", 0.01)),
        n_fft=int(n_fft),
        mel_bands=int(preprocessor.get("features", 64)),
        preemphasis=float(preprocessor.get("preemph", 0.97) or 0.0),
        normalize="none" if normalize in (None, "NA", "none") else str(normalize),
    )
    return Manifest(settings, int(max_symbols or 10))


def vocabulary_lines(tokens: Sequence[str]) -> str:
    return "".join(f"{token} {index}\n" for index, token in enumerate([*tokens, "<blk>"]))


def export(nemo_path: Path, out_dir: Path) -> None:
    try:
        import nemo.collections.asr as nemo_asr
        from omegaconf import OmegaConf
    except ImportError:
        raise ModelError(
            "export-nemo needs NeMo: pip install 'speech-event[export]' (nemo_toolkit and torch); "
            "only for exporting, never on the robot"
        ) from None
    model = nemo_asr.models.ASRModel.restore_from(str(nemo_path), map_location="cpu")
    model.eval()
    preprocessor: Dict[str, Any] = OmegaConf.to_container(model.cfg.preprocessor, resolve=True)
    greedy = OmegaConf.to_container(model.cfg.decoding, resolve=True).get("greedy", {})
    manifest = manifest_from_preprocessor(preprocessor, greedy.get("max_symbols"))
    tokens: List[str] = list(model.joint.vocabulary)
    out_dir.mkdir(parents=True, exist_ok=True)
    model.export(str(out_dir / "model.onnx"))
    (out_dir / "vocab.txt").write_text(vocabulary_lines(tokens), encoding="utf-8")
    (out_dir / MANIFEST_FILE).write_text(json.dumps(manifest_json(manifest), indent=2), encoding="utf-8")


def main(argv: List[str]) -> int:
    parser = argparse.ArgumentParser(prog="speech-event export-nemo", description=__doc__)
    parser.add_argument("nemo", type=Path, help="the .nemo file of a NeMo conformer-transducer")
    parser.add_argument("out_dir", type=Path, help="the model directory to write")
    arguments = parser.parse_args(argv)
    try:
        export(arguments.nemo, arguments.out_dir)
    except ModelError as problem:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    print(f"wrote {arguments.out_dir}: set rw_model_path or en_model_path to it")
    return 0
