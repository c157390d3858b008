"""The tones transducer (fixtures/tones_model.py) through the real NeMo engine."""

import dataclasses
from pathlib import Path
from typing import Any, Tuple

import numpy as np
import onnx_asr
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fixtures.audio import noise, normalise_text, speak_tones
from fixtures.tones_model import SETTINGS, build_tones_model, tones_model_directory
from harness.memory_runner import run_in_memory
from harness.report import passed, report
from harness.scenario import load_scenario
from speech_event.asr.engine import NemoRecognizer
from speech_event.asr.features import features
from speech_event.config import SpeechEventConfig
from speech_event.resample import resample
from tests.scenario_files import TONES_SCENARIOS
from tests.strategies import TONES_TEXT

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def engine() -> NemoRecognizer:
    return NemoRecognizer(tones_model_directory())


def test_it_is_built_in_nemo_s_export_layout(tmp_path: Path) -> None:
    model = build_tones_model(tmp_path / "tones")
    assert sorted(path.name for path in model.iterdir()) == [
        "config.json",
        "decoder_joint-model.onnx",
        "encoder-model.onnx",
        "vocab.txt",
    ]


@settings(max_examples=40, deadline=None)
@given(text=TONES_TEXT, seed=st.integers(0, 2**16), level_db=st.sampled_from([-60.0, -45.0, -40.0]))
def test_any_text_round_trips_through_the_real_engine(
    engine: NemoRecognizer, text: str, seed: int, level_db: float
) -> None:
    spoken = speak_tones(text, 48000)
    noisy = spoken + noise(spoken.size, level_db, np.random.default_rng(seed))
    assert engine.transcribe(resample(noisy, 48000, 16000)).text == normalise_text(text)


@given(seed=st.integers(0, 2**16), seconds=st.floats(0.1, 3.0))
@settings(max_examples=20, deadline=None)
def test_noise_alone_transcribes_to_nothing(engine: NemoRecognizer, seed: int, seconds: float) -> None:
    assert engine.transcribe(noise(int(seconds * 16000), -40.0, np.random.default_rng(seed))).text == ""


@pytest.mark.parametrize("model", ["fixture-model", "fixture-parakeet", "fixture-whisper"])
@pytest.mark.parametrize("path", TONES_SCENARIOS, ids=[path.stem for path in TONES_SCENARIOS])
def test_every_tones_scenario_passes_with_the_fixture_models_as_with_the_fake(path: Path, model: str) -> None:
    scenario = load_scenario(path, SpeechEventConfig())
    with_fake = run_in_memory(dataclasses.replace(scenario, recognizer="fake"))
    with_model = run_in_memory(dataclasses.replace(scenario, recognizer=model))
    assert passed(scenario, with_model), report(scenario, with_model)
    assert with_model == with_fake  # the same messages, responses and results at the same times


class _OurFeatures:
    """An onnx-asr preprocessor that hands it the features our engine computed."""

    def __call__(self, waveforms: np.ndarray, lengths: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        computed = np.stack(
            [features(waveform[:length], SETTINGS) for waveform, length in zip(waveforms, lengths)]
        )
        return computed.astype(np.float32), np.array([computed.shape[2]] * len(waveforms), np.int64)


@pytest.mark.parametrize("text", ["go to the kitchen", "mmm i'll see you", "a b c d e f g"])
def test_onnx_asr_decodes_the_fixture_model_to_the_same_text(engine: NemoRecognizer, text: str) -> None:
    audio = resample(speak_tones(text, 48000), 48000, 16000)
    reference = onnx_asr.load_model("nemo-conformer-rnnt", tones_model_directory())
    # onnx-asr's preprocessor computes the conformer features; this model asks for other ones, so
    # onnx-asr is handed ours and runs its own encoder call, greedy decoding and detokenisation.
    inner: Any = reference.asr  # onnx-asr's own ASR object; its preprocessor is a plug-in component
    inner._preprocessor = _OurFeatures()
    assert engine.transcribe(audio).text == reference.recognize(audio) == normalise_text(text)
