"""onnx-asr's NeMo model directories load as they are: directories written in exactly its layout
(our random-weight models' ONNX files, vocab.txt, onnx-asr's config.json or none) read as the same
manifest as our own layout and give the same tokens, through our engine and through onnx-asr."""

import dataclasses
import json
import shutil
from pathlib import Path
from typing import Any, Callable, Dict, Optional, Tuple

import numpy as np
import onnx
import onnx_asr
import pytest
from onnx import helper

from fixtures.audio import noise, speak_tones
from fixtures.transducer_model import build_random_ctc, build_random_transducer
from speech_event.config import SpeechEventConfig
from speech_event.errors import ModelError
from speech_event.pipeline.resample import resample
from speech_event.recognizers import RECOGNIZERS
from speech_event.recognizers.nemo.manifest import CTC, RNNT, TDT, load_manifest
from speech_event.recognizers.nemo.recognizer import NemoRecognizer
from speech_event.recognizers.onnx.families import family_of

NEMO_DIRECTORY = (
    "a model directory holds encoder-model.onnx, decoder_joint-model.onnx (a transducer) or model.onnx "
    "(CTC), vocab.txt and config.json (speech-event export-nemo MODEL.nemo DIR writes one)"
)
Build = Callable[[Path, int], Path]
FORMATS: Dict[str, Tuple[str, Build]] = {
    RNNT: (
        "conformer-transducer",
        lambda path, bands: build_random_transducer(path, seed=1, mel_bands=bands),
    ),
    TDT: (
        "parakeet",
        lambda path, bands: build_random_transducer(path, seed=1, durations=(0, 1, 2, 3, 4), mel_bands=bands),
    ),
    CTC: ("parakeet", lambda path, bands: build_random_ctc(path, seed=1, mel_bands=bands)),
}
CASES = [(decoding, bands) for decoding in FORMATS for bands in (80, 128)]


@pytest.fixture(scope="module")
def audio() -> np.ndarray:
    return np.concatenate(
        [
            noise(16000, -30.0, np.random.default_rng(1)),
            resample(speak_tones("muraho", 48000), 48000, 16000),
        ]
    )


@pytest.fixture(scope="module")
def ours(tmp_path_factory: pytest.TempPathFactory) -> Callable[[str, int], Path]:
    """Our own layout of each decoding and feature count, built once."""
    built: Dict[Tuple[str, int], Path] = {}

    def model(decoding: str, bands: int) -> Path:
        if (decoding, bands) not in built:
            path = tmp_path_factory.mktemp("ours") / f"{decoding}-{bands}"
            built[decoding, bands] = FORMATS[decoding][1](path, bands)
        return built[decoding, bands]

    return model


def onnx_asr_config(decoding: str, bands: int) -> Dict[str, Any]:
    """config.json as onnx-asr's conversion guide writes it: its four keys, nothing of ours."""
    return {
        "model_type": decoding,
        "features_size": bands,
        "subsampling_factor": 4,
        "max_tokens_per_step": 10,
    }


def onnx_asr_directory(ours: Path, target: Path, config: Optional[Dict[str, Any]]) -> Path:
    """``ours``'s ONNX files and vocab.txt in ``target``, with onnx-asr's ``config`` (None: no config.json)."""
    target.mkdir(parents=True)
    for path in ours.iterdir():
        if path.name != "config.json":
            shutil.copyfile(path, target / path.name)
    if config is not None:
        (target / "config.json").write_text(json.dumps(config, indent=4))
    return target


@pytest.mark.parametrize(("decoding", "bands"), CASES)
def test_an_onnx_asr_directory_reads_as_our_manifest_and_gives_the_same_tokens(
    tmp_path: Path, ours: Callable[[str, int], Path], audio: np.ndarray, decoding: str, bands: int
) -> None:
    own = ours(decoding, bands)
    theirs = onnx_asr_directory(own, tmp_path / "theirs", onnx_asr_config(decoding, bands))
    manifest = load_manifest(theirs / "config.json")
    assert manifest == load_manifest(own / "config.json")
    assert (manifest.features.mel_bands, manifest.family) == (bands, FORMATS[decoding][0])
    found = NemoRecognizer(theirs).hypothesis(audio)
    assert found.tokens != []
    assert found == NemoRecognizer(own).hypothesis(audio)


@pytest.mark.parametrize(("decoding", "bands"), CASES)
def test_onnx_asr_itself_gives_the_same_text_on_its_own_layout(
    tmp_path: Path, ours: Callable[[str, int], Path], audio: np.ndarray, decoding: str, bands: int
) -> None:
    theirs = onnx_asr_directory(ours(decoding, bands), tmp_path / "theirs", onnx_asr_config(decoding, bands))
    text = NemoRecognizer(theirs).transcribe(audio).text
    assert text != ""
    assert onnx_asr.load_model(path=theirs, model=decoding).recognize(audio) == text


@pytest.mark.parametrize("decoding", list(FORMATS))
def test_without_config_json_the_files_say_the_decoding_and_family(
    tmp_path: Path, ours: Callable[[str, int], Path], audio: np.ndarray, decoding: str
) -> None:
    own = ours(decoding, 80)
    theirs = onnx_asr_directory(own, tmp_path / "theirs", None)
    manifest = load_manifest(theirs / "config.json")
    assert manifest.subsampling_factor == 8  # onnx-asr's default; our fixtures' encoders subsample by 4
    assert dataclasses.replace(manifest, subsampling_factor=4) == load_manifest(own / "config.json")
    assert family_of(theirs, unrecorded="unrecorded") == FORMATS[decoding][0]
    assert NemoRecognizer(theirs).hypothesis(audio) == NemoRecognizer(own).hypothesis(audio)


def _unfix_logits(joint: Path) -> None:
    """The joint's logits dimension made one onnxruntime cannot infer (reshaped to its own runtime
    shape), as a joint whose output layer is not a fixed weight would be."""
    model = onnx.load(str(joint))
    for node in model.graph.node:
        node.output[:] = ["fixed_outputs" if name == "outputs" else name for name in node.output]
    model.graph.node.extend(
        [
            helper.make_node("Shape", ["fixed_outputs"], ["outputs_shape"]),
            helper.make_node("Reshape", ["fixed_outputs", "outputs_shape"], ["outputs"]),
        ]
    )
    model.graph.output[0].type.tensor_type.shape.dim[3].dim_param = "logits"
    onnx.save(model, str(joint))


def test_tdt_durations_are_as_many_as_the_joint_gives_logits_after_the_vocabulary(tmp_path: Path) -> None:
    model = build_random_transducer(tmp_path / "ours", durations=(0, 1, 2))
    theirs = onnx_asr_directory(model, tmp_path / "theirs", onnx_asr_config(TDT, 80))
    assert load_manifest(theirs / "config.json").durations == (0, 1, 2)
    # a joint that does not fix its logits: NeMo's default durations
    _unfix_logits(theirs / "decoder_joint-model.onnx")
    assert load_manifest(theirs / "config.json").durations == (0, 1, 2, 3, 4)


def test_recorded_keys_win_over_the_derived_ones(tmp_path: Path, ours: Callable[[str, int], Path]) -> None:
    config = {**onnx_asr_config(TDT, 80), "durations": [0, 2, 4, 6, 8], "max_tokens_per_step": 3}
    theirs = onnx_asr_directory(ours(TDT, 80), tmp_path / "theirs", config)
    manifest = load_manifest(theirs / "config.json")
    assert (manifest.durations, manifest.max_symbols_per_step) == ((0, 2, 4, 6, 8), 3)


@pytest.mark.parametrize(
    ("config", "family"),
    [
        (onnx_asr_config(RNNT, 80), "conformer-transducer"),
        (onnx_asr_config(TDT, 128), "parakeet"),
        (onnx_asr_config(CTC, 80), "parakeet"),
        ({"model_type": "whisper", "num_mel_bins": 80}, "whisper"),  # Hugging Face optimum's Whisper
        ({"model_type": "nemo-conformer-aed"}, "unrecorded"),
    ],
)
def test_family_of_names_the_family_of_an_onnx_asr_directory(
    tmp_path: Path, config: Dict[str, Any], family: str
) -> None:
    (tmp_path / "config.json").write_text(json.dumps(config))
    assert family_of(tmp_path, unrecorded="unrecorded") == family


def test_family_of_a_directory_it_cannot_understand_is_the_unrecorded_one(tmp_path: Path) -> None:
    assert family_of(tmp_path, unrecorded="unrecorded") == "unrecorded"
    assert family_of(tmp_path / "absent", unrecorded="unrecorded") == "unrecorded"


def test_the_node_runs_an_onnx_asr_parakeet_directory_with_model_parakeet(
    tmp_path: Path, ours: Callable[[str, int], Path], audio: np.ndarray
) -> None:
    theirs = onnx_asr_directory(ours(TDT, 128), tmp_path / "theirs", onnx_asr_config(TDT, 128))
    config = SpeechEventConfig(language="english", model="parakeet", en_model_path=str(theirs))
    recognizer = RECOGNIZERS["auto"](config)
    assert recognizer.transcribe(audio).text == NemoRecognizer(ours(TDT, 128)).transcribe(audio).text
    wrong = dataclasses.replace(config, model="conformer-transducer")
    with pytest.raises(ModelError) as error:
        RECOGNIZERS["auto"](wrong)
    assert str(error.value).startswith(f"{theirs} holds a parakeet model")


@pytest.mark.parametrize("decoding", list(FORMATS))
def test_a_directory_of_int8_files_only_loads_them(
    tmp_path: Path, ours: Callable[[str, int], Path], audio: np.ndarray, decoding: str
) -> None:
    own = ours(decoding, 80)
    theirs = onnx_asr_directory(own, tmp_path / "theirs", onnx_asr_config(decoding, 80))
    for model in theirs.glob("*.onnx"):
        model.rename(model.with_name(model.name.replace(".onnx", ".int8.onnx")))
    assert NemoRecognizer(theirs).hypothesis(audio) == NemoRecognizer(own).hypothesis(audio)


def _error(directory: Path) -> str:
    with pytest.raises(ModelError) as error:
        NemoRecognizer(directory)
    return str(error.value)


@pytest.mark.parametrize("missing", ["encoder-model.onnx", "decoder_joint-model.onnx", "vocab.txt"])
def test_a_transducer_without_config_json_names_the_file_it_misses(
    tmp_path: Path, ours: Callable[[str, int], Path], missing: str
) -> None:
    theirs = onnx_asr_directory(ours(RNNT, 80), tmp_path / "theirs", None)
    (theirs / missing).unlink()
    assert _error(theirs) == f"{theirs}: missing {missing}; {NEMO_DIRECTORY}"


def test_a_directory_without_config_json_or_model_files_says_so(
    tmp_path: Path, ours: Callable[[str, int], Path]
) -> None:
    theirs = onnx_asr_directory(ours(CTC, 80), tmp_path / "theirs", None)
    (theirs / "model.onnx").unlink()
    assert _error(theirs) == f"{theirs}: missing config.json and the model's ONNX files; {NEMO_DIRECTORY}"


def test_a_joint_that_does_not_fix_its_logits_needs_model_type(
    tmp_path: Path, ours: Callable[[str, int], Path]
) -> None:
    theirs = onnx_asr_directory(ours(TDT, 80), tmp_path / "theirs", None)
    _unfix_logits(theirs / "decoder_joint-model.onnx")
    assert _error(theirs) == (
        f"{theirs / 'decoder_joint-model.onnx'}: its logits per step are not fixed in the file, so RNN-T "
        "and TDT cannot be told apart: config.json needs model_type (nemo-conformer-rnnt or nemo-conformer-tdt)"
    )


def test_a_model_type_of_onnx_asr_that_the_engine_does_not_run_is_named(
    tmp_path: Path, ours: Callable[[str, int], Path]
) -> None:
    theirs = onnx_asr_directory(ours(RNNT, 80), tmp_path / "theirs", {"model_type": "nemo-conformer-aed"})
    assert _error(theirs) == (
        f"{theirs / 'config.json'}: not a usable model config (ValueError(\"model_type 'nemo-conformer-aed' "
        'is not one of nemo-conformer-rnnt, nemo-conformer-tdt, nemo-conformer-ctc")); it needs sample_rate, '
        "window_size, window_stride, n_fft and features, as in NeMo's preprocessor config, and names its "
        "model_type, family and (TDT) durations as speech-event export-nemo writes them"
    )
