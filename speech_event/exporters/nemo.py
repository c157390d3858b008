"""``speech-event export-nemo MODEL.nemo OUT_DIR``: a .nemo model to the directory the engine loads.

Transducers (RNN-T, and TDT: the joint also gives durations) and CTC models, and hybrid RNN-T/CTC
models (Parakeet), whose RNN-T head is exported unless ``--head ctc`` asks for the CTC one.
NeMo's own exporter writes the ONNX files (``model.export("model.onnx")``: encoder-model.onnx and
decoder_joint-model.onnx for a transducer, model.onnx for CTC); vocab.txt comes from the head's
vocabulary with the blank last; config.json from the model's own config: the preprocessor, the
encoder's subsampling factor, the decoding (TDT's durations, greedy max_symbols) and the family
(parakeet for hybrid, TDT, CTC and FastConformer models; conformer-transducer otherwise).
Needs nemo_toolkit (the ``export`` extra) on a workstation; never on the robot.
"""

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Sequence

from speech_event.errors import ModelError
from speech_event.exporters.quantize import INT8_HELP, quantize_and_say
from speech_event.recognizers.nemo.features import FeatureSettings
from speech_event.recognizers.nemo.manifest import (
    CONFORMER_TRANSDUCER,
    CTC,
    MANIFEST_FILE,
    NEMO_FAMILIES,
    PARAKEET,
    RNNT,
    TDT,
    Manifest,
    manifest_json,
)

# Preprocessor settings our features implement, and the value NeMo uses when the config omits one.
_SUPPORTED = {"window": "hann", "log": True, "frame_splicing": 1, "mag_power": 2.0, "pad_to": 0}
_DEFAULTS = {"window": "hann", "log": True, "frame_splicing": 1, "mag_power": 2.0, "pad_to": 16}
HEADS = ("rnnt", "ctc")


def feature_settings(preprocessor: Mapping[str, Any]) -> FeatureSettings:
    """Our features from NeMo's AudioToMelSpectrogramPreprocessor config, or why they cannot be."""
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
    return FeatureSettings(
        sample_rate=rate,
        window_seconds=window,
        stride_seconds=float(preprocessor.get("window_stride", 0.01)),
        n_fft=int(n_fft),
        mel_bands=int(preprocessor.get("features", 64)),
        preemphasis=float(preprocessor.get("preemph", 0.97) or 0.0),
        normalize="none" if normalize in (None, "NA", "none") else str(normalize),
    )


def manifest_for(
    config: Mapping[str, Any], hybrid: bool, ctc: bool, family: Optional[str] = None
) -> Manifest:
    """Our manifest from a NeMo model's whole config (``model.cfg``). ``hybrid``: an RNN-T/CTC
    model; ``ctc``: the CTC decoding is exported (a CTC model, or a hybrid model's CTC head)."""
    encoder = config.get("encoder") or {}
    decoding = config.get("decoding") or {}
    tdt = not ctc and (decoding.get("model_type") == "tdt" or bool(decoding.get("durations")))
    durations = tuple(int(d) for d in decoding.get("durations") or ()) if tdt else ()
    if tdt and not durations:
        raise ModelError("a TDT model whose config has no decoding.durations: cannot tell its durations")
    fast_conformer = encoder.get("subsampling") == "dw_striding"
    detected = PARAKEET if hybrid or ctc or tdt or fast_conformer else CONFORMER_TRANSDUCER
    greedy = decoding.get("greedy") or {}
    return Manifest(
        feature_settings(config["preprocessor"]),
        max_symbols_per_step=int(greedy.get("max_symbols") or 10),
        decoding=CTC if ctc else TDT if tdt else RNNT,
        family=family or detected,
        subsampling_factor=int(encoder.get("subsampling_factor", 4)),
        durations=durations,
    )


def vocabulary_lines(tokens: Sequence[str]) -> str:
    """vocab.txt's text: one ``token id`` a line, the blank (``<blk>``) added last."""
    return "".join(f"{token} {index}\n" for index, token in enumerate([*tokens, "<blk>"]))


def export(nemo_path: Path, out_dir: Path, head: str = "rnnt", family: Optional[str] = None) -> Manifest:
    """Export the .nemo file at ``nemo_path`` to ``out_dir``; its manifest, or ModelError without NeMo."""
    try:
        import nemo.collections.asr as nemo_asr
    except ImportError:
        raise ModelError(
            "export-nemo needs NeMo: pip install 'speech-event[export]' (nemo_toolkit and torch); "
            "only for exporting, never on the robot"
        ) from None
    model = nemo_asr.models.ASRModel.restore_from(str(nemo_path), map_location="cpu")
    return export_model(model, out_dir, head, family, name=str(nemo_path))


def export_model(
    model: Any, out_dir: Path, head: str = "rnnt", family: Optional[str] = None, name: str = "the model"
) -> Manifest:
    """A loaded NeMo ASR model to a model directory."""
    from omegaconf import OmegaConf

    model.eval()
    hybrid = hasattr(model, "joint") and hasattr(model, "ctc_decoder")
    ctc = not hasattr(model, "joint") or head == "ctc"
    if head == "ctc" and not (hybrid or ctc):
        raise ModelError(f"{name}: a {type(model).__name__} has no CTC head; leave out --head ctc")
    config: Dict[str, Any] = OmegaConf.to_container(model.cfg, resolve=True)
    manifest = manifest_for(config, hybrid, ctc, family)
    if hybrid and ctc:
        model.set_export_config({"decoder_type": "ctc"})
        tokens: List[str] = list(model.ctc_decoder.vocabulary)
    else:
        tokens = list(model.decoder.vocabulary if ctc else model.joint.vocabulary)
    out_dir.mkdir(parents=True, exist_ok=True)
    model.export(str(out_dir / "model.onnx"))
    (out_dir / "vocab.txt").write_text(vocabulary_lines(tokens), encoding="utf-8")
    (out_dir / MANIFEST_FILE).write_text(json.dumps(manifest_json(manifest), indent=2), encoding="utf-8")
    return manifest


def main(argv: List[str]) -> int:
    """The ``speech-event export-nemo`` command; returns its exit status."""
    parser = argparse.ArgumentParser(prog="speech-event export-nemo", description=__doc__)
    parser.add_argument("nemo", type=Path, help="the .nemo file of a NeMo ASR model")
    parser.add_argument("out_dir", type=Path, help="the model directory to write")
    parser.add_argument(
        "--head",
        choices=HEADS,
        default="rnnt",
        help="a hybrid RNN-T/CTC model's head to export (default rnnt)",
    )
    parser.add_argument(
        "--family",
        choices=NEMO_FAMILIES,
        help="the robot's model setting it serves (default: from the model)",
    )
    parser.add_argument("--int8", action="store_true", help=INT8_HELP)
    arguments = parser.parse_args(argv)
    try:
        manifest = export(arguments.nemo, arguments.out_dir, arguments.head, arguments.family)
    except ModelError as problem:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    written = f"wrote {arguments.out_dir} ({manifest.family}, {manifest.decoding})"
    print(f"{written}: set model {manifest.family}, and rw_model_path or en_model_path to it")
    if arguments.int8:
        quantize_and_say(arguments.out_dir)
    return 0
