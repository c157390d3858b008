"""The parakeet family's formats (TDT, CTC) beside the conformer's RNN-T: decoding, the model
directory's checks, and the family the robot's ``model`` key asks for."""

import json
from pathlib import Path
from typing import Any, Callable, Dict, List, Tuple

import numpy as np
import onnx_asr
import pytest

from fixtures.audio import noise, speak_tones
from fixtures.tones_model import tones_model_directory, tones_tdt_model_directory
from fixtures.transducer_model import build_random_ctc, build_random_transducer
from fixtures.whisper_tones_model import whisper_tones_model_directory
from speech_event.config import SpeechEventConfig
from speech_event.errors import ModelError
from speech_event.pipeline.resample import resample
from speech_event.recognizers import RECOGNIZERS
from speech_event.recognizers.nemo.ctc import ctc_greedy
from speech_event.recognizers.nemo.recognizer import NemoRecognizer
from speech_event.recognizers.nemo.tdt import tdt_greedy
from speech_event.recognizers.onnx.hypothesis import log_softmax
from speech_event.recognizers.whisper.recognizer import WhisperRecognizer

BLANK = 3
DURATIONS = (0, 1, 2)


def _logits(token: int, duration: int) -> np.ndarray:
    """Token logits (blank last) then duration logits, with ``token`` and ``duration`` the best."""
    logits = np.zeros(BLANK + 1 + len(DURATIONS))
    logits[token] = 2.0
    logits[BLANK + 1 + DURATIONS.index(duration)] = 1.0
    return logits


def test_tdt_decoding_moves_on_by_the_predicted_durations() -> None:
    # frame 0: token 1 staying (duration 0), token 2 moving on 2 frames; frame 2: blank with
    # duration 0 (moves on 1 all the same); frame 3: token 0 staying, until max_symbols (3) on one
    # frame moves on by 1; frame 4: blank moving on 2, past the end.
    script: Dict[Tuple[int, int], Tuple[int, int]] = {
        (0, BLANK): (1, 0),
        (0, 1): (2, 2),
        (2, 2): (BLANK, 0),
        (3, 2): (0, 0),
        (3, 0): (0, 0),
        (4, 0): (BLANK, 2),
    }
    calls: List[Tuple[int, int, int]] = []

    def step(frame: np.ndarray, last: int, state: int) -> Tuple[np.ndarray, int]:
        calls.append((int(frame[0]), last, state))
        return _logits(*script[(int(frame[0]), last)]), state + 1

    frames = np.arange(6, dtype=np.float64)[:, None]
    found = tdt_greedy(frames, step, 0, BLANK, DURATIONS, max_symbols=3)
    assert found.tokens == [1, 2, 0, 0, 0]
    # frame 1 is skipped; the state moves on only with a token
    assert calls == [(0, 3, 0), (0, 1, 1), (2, 2, 2), (3, 2, 2), (3, 0, 3), (3, 0, 4), (4, 0, 5)]
    token_log_probability = float(log_softmax(_logits(0, 0)[: BLANK + 1])[0])
    assert found.score == pytest.approx(5 * token_log_probability)


def test_ctc_decoding_merges_repeats_and_drops_blanks_scoring_every_frame() -> None:
    best = [1, 1, BLANK, 1, 2, 2, BLANK, BLANK, 0]
    logits = np.full((len(best), BLANK + 1), -3.0)
    logits[np.arange(len(best)), best] = -0.1
    found = ctc_greedy(logits, BLANK)
    assert found.tokens == [1, 1, 2, 0]
    assert found.score == pytest.approx(len(best) * float(log_softmax(logits[0])[1]))


SEEDS = [0, 1, 2]


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize(
    ("model_type", "build"),
    [
        (
            "nemo-conformer-tdt",
            lambda path, seed: build_random_transducer(path, seed, durations=(0, 1, 2, 3, 4)),
        ),
        ("nemo-conformer-ctc", build_random_ctc),
    ],
)
def test_the_engine_gives_the_same_text_as_onnx_asr_on_parakeet_formats(
    tmp_path: Path, model_type: str, build: object, seed: int
) -> None:
    model = build(tmp_path / "model", seed)  # type: ignore[operator]
    audio = np.concatenate(
        [
            noise(16000, -30.0, np.random.default_rng(seed)),
            resample(speak_tones("muraho", 48000), 48000, 16000),
        ]
    )
    text = NemoRecognizer(model).transcribe(audio).text
    assert text != ""
    assert text == onnx_asr.load_model(model_type, model).recognize(audio)


def test_the_tdt_fixture_model_skips_frames(monkeypatch: pytest.MonkeyPatch) -> None:
    engine = NemoRecognizer(tones_tdt_model_directory())
    audio = resample(speak_tones("go to the kitchen", 48000), 48000, 16000)
    model = engine._model  # the engine's own model: count the decoder-joint's steps
    step = model.step  # type: ignore[union-attr]
    steps: List[int] = []

    def counted(*arguments: Any, **options: Any) -> Any:
        steps.append(1)
        return step(*arguments, **options)

    monkeypatch.setattr(model, "step", counted)
    assert engine.transcribe(audio).text == "go to the kitchen"
    frames = audio.size // 80  # 5 ms frames
    assert len(steps) < 0.6 * frames  # RNN-T would take a step per frame, and one per letter more


def test_confidence_is_the_exp_of_the_hypothesis_score() -> None:
    engine = NemoRecognizer(tones_model_directory())
    audio = resample(speak_tones("yes", 48000), 48000, 16000)
    transcript = engine.transcribe(audio)
    assert transcript.confidence == pytest.approx(np.exp(engine.hypothesis(audio).score))
    assert 0.0 < transcript.confidence < 1.0  # type: ignore[operator]


def _edit_config(model: Path, **changes: object) -> None:
    path = model / "config.json"
    document = json.loads(path.read_text())
    document.update(changes)
    path.write_text(json.dumps(document))


def test_a_tdt_directory_without_its_durations_is_named(tmp_path: Path) -> None:
    model = build_random_transducer(tmp_path / "tdt", durations=(0, 1, 2))
    _edit_config(model, durations=[])
    with pytest.raises(ModelError) as error:
        NemoRecognizer(model)
    assert str(error.value) == (
        f"{model / 'config.json'}: not a usable model config (ValueError('a TDT model needs its durations "
        "(frames, 0 or more), e.g. [0, 1, 2, 3, 4]')); it needs sample_rate, window_size, window_stride, "
        "n_fft and features, as in NeMo's preprocessor config, and names its model_type, family and (TDT) "
        "durations as speech-event export-nemo writes them"
    )


def test_logits_that_do_not_match_the_vocabulary_and_durations_are_named(tmp_path: Path) -> None:
    model = build_random_transducer(tmp_path / "tdt", durations=(0, 1, 2))
    _edit_config(model, durations=[0, 1, 2, 3])
    with pytest.raises(ModelError) as error:
        NemoRecognizer(model)
    assert str(error.value) == (
        f"{model}: the model gives 56 logits per step, but vocab.txt has 53 tokens (blank included) and "
        "4 durations in config.json: the files are not of one export"
    )


def test_an_unknown_decoding_is_named(tmp_path: Path) -> None:
    model = build_random_ctc(tmp_path / "ctc")
    _edit_config(model, model_type="nemo-conformer-aed")
    with pytest.raises(ModelError) as error:
        NemoRecognizer(model)
    assert (
        "model_type 'nemo-conformer-aed' is not one of nemo-conformer-rnnt, nemo-conformer-tdt, nemo-conformer-ctc"
        in str(error.value)
    )


def test_a_ctc_directory_without_its_model_file_says_what_a_directory_holds(tmp_path: Path) -> None:
    model = build_random_ctc(tmp_path / "ctc")
    (model / "model.onnx").unlink()
    with pytest.raises(ModelError) as error:
        NemoRecognizer(model)
    assert str(error.value).startswith(f"{model}: missing model.onnx; a model directory holds")


@pytest.mark.parametrize(
    ("model", "directory", "family"),
    [
        ("parakeet", tones_model_directory, "conformer-transducer"),
        ("conformer-transducer", tones_tdt_model_directory, "parakeet"),
        ("parakeet", whisper_tones_model_directory, "whisper"),
        ("whisper", tones_tdt_model_directory, "parakeet"),
    ],
)
def test_a_directory_of_another_family_than_model_names_is_one_clear_error(
    model: str, directory: Callable[[], Path], family: str
) -> None:
    path = directory()
    config = SpeechEventConfig(language="english", model=model, en_model_path=str(path))
    with pytest.raises(ModelError) as error:
        RECOGNIZERS["auto"](config)
    assert str(error.value) == (
        f"{path} holds a {family} model (config.json: family), but model is {model}: set model {family}, "
        f"or give a directory exported from a {model} model"
    )


@pytest.mark.parametrize(
    ("model", "directory", "engine"),
    [
        ("parakeet", tones_tdt_model_directory, NemoRecognizer),
        ("whisper", whisper_tones_model_directory, WhisperRecognizer),
    ],
)
def test_auto_loads_the_directories_of_both_languages_with_the_engine_of_model(
    model: str, directory: Callable[[], Path], engine: type
) -> None:
    path = str(directory())
    for language in ("english", "kinyarwanda"):
        config = SpeechEventConfig(language=language, model=model, en_model_path=path, rw_model_path=path)
        recognizer = RECOGNIZERS["auto"](config)
        assert isinstance(recognizer, engine)
        assert recognizer.transcribe(resample(speak_tones("yego", 48000), 48000, 16000)).text == "yego"


def test_model_parakeet_without_a_directory_does_not_fall_back_to_pocketsphinx() -> None:
    with pytest.raises(ModelError) as error:
        RECOGNIZERS["auto"](SpeechEventConfig(language="english", model="parakeet"))
    assert str(error.value) == (
        "language english with model parakeet needs en_model_path: the directory of an exported parakeet model "
        "(speech-event export-nemo MODEL.nemo DIR writes one)"
    )


def test_audio_under_a_second_is_padded_with_silence_on_both_sides_as_nemo_transcribe_does(
    tmp_path: Path,
) -> None:
    engine = NemoRecognizer(build_random_transducer(tmp_path / "model"))
    speech = noise(8000, -20.0, np.random.default_rng(3))
    padded = np.concatenate([np.zeros(4000), speech, np.zeros(4000)]).astype(np.float32)
    after = np.concatenate([speech, np.zeros(8000)]).astype(np.float32)
    assert engine.hypothesis(speech) == engine.hypothesis(padded)
    assert engine.hypothesis(speech) != engine.hypothesis(after)  # where the silence goes matters
    longer = noise(16000, -20.0, np.random.default_rng(3))
    assert engine.hypothesis(longer) != engine.hypothesis(np.concatenate([longer, np.zeros(800, np.float32)]))
