"""One utterance's recognition alone (speech_event/pipeline/recognition.py): resample, screen,
transcribe, timed; it never raises."""

from typing import Iterator, List

import numpy as np

from fixtures.fakes import HEARD, FailingRecognizer, SpyRecognizer
from speech_event.pipeline.recognition import Recognition
from speech_event.pipeline.recognition_queue import RecognitionOutcome
from speech_event.pipeline.screen import Discard, SpeechScreen
from speech_event.ports import Transcript

NO_SCREEN = SpeechScreen(0.0, 0.0, None)


class Stopwatch:
    """Gives the times it is told to, in order; counts the readings."""

    def __init__(self, *times: float) -> None:
        self._times: Iterator[float] = iter(times)
        self.readings = 0

    def __call__(self) -> float:
        self.readings += 1
        return next(self._times)


class ExitingRecognizer(SpyRecognizer):
    def transcribe(self, audio: np.ndarray) -> Transcript:
        raise SystemExit(3)


class StoppedRecognizer(SpyRecognizer):
    """Runs a while on the stopwatch, then raises as a stopped engine does."""

    def __init__(self, stopwatch: List[float]) -> None:
        super().__init__()
        self._stopwatch = stopwatch

    def transcribe(self, audio: np.ndarray) -> Transcript:
        self._stopwatch[0] += 0.75
        raise RuntimeError("terminated")


def test_the_engine_gets_the_audio_at_its_own_rate() -> None:
    engine = SpyRecognizer()  # 16 kHz
    recognize = Recognition(48000, NO_SCREEN, Stopwatch(0.0, 0.0))
    recognize(np.zeros(48000, dtype=np.float32), engine)
    assert [(audio.size, str(audio.dtype)) for audio in engine.utterances] == [(16000, "float32")]


def test_audio_already_at_the_engines_rate_is_given_as_it_is() -> None:
    engine = SpyRecognizer()
    audio = np.linspace(-0.5, 0.5, 16000, dtype=np.float32)
    Recognition(16000, NO_SCREEN, Stopwatch(0.0, 0.0))(audio, engine)
    assert len(engine.utterances) == 1
    np.testing.assert_array_equal(engine.utterances[0], audio)


def test_the_outcome_is_the_engines_answer_and_the_time_the_stopwatch_measured() -> None:
    stopwatch = Stopwatch(3.0, 5.25)
    outcome = Recognition(16000, NO_SCREEN, stopwatch)(np.zeros(16000, dtype=np.float32), SpyRecognizer())
    assert outcome == RecognitionOutcome(HEARD, discard=None, took=2.25, error=None)
    assert stopwatch.readings == 2


def test_the_answer_is_passed_on_unchecked() -> None:
    """Checking the answer is publication's work, under the utterance's number."""
    engine = SpyRecognizer(answer=Transcript("go", confidence=7.0))
    outcome = Recognition(16000, NO_SCREEN, Stopwatch(0.0, 1.0))(np.zeros(160, dtype=np.float32), engine)
    assert outcome == RecognitionOutcome(Transcript("go", confidence=7.0), took=1.0)


def test_an_utterance_too_short_is_discarded_untranscribed_and_untimed() -> None:
    engine = SpyRecognizer()
    stopwatch = Stopwatch()
    recognize = Recognition(16000, SpeechScreen(0.5, 0.0, None), stopwatch)
    outcome = recognize(np.zeros(7999, dtype=np.float32), engine)
    assert outcome == RecognitionOutcome(discard=Discard.TOO_SHORT)
    assert engine.utterances == []
    assert stopwatch.readings == 0


def test_the_screen_measures_the_length_at_the_engines_rate() -> None:
    engine = SpyRecognizer()
    recognize = Recognition(48000, SpeechScreen(0.5, 0.0, None), Stopwatch(0.0, 0.0))
    assert recognize(np.zeros(24000, dtype=np.float32), engine).discard is None
    assert [audio.size for audio in engine.utterances] == [8000]


def test_an_utterance_below_the_vad_threshold_is_discarded() -> None:
    engine = SpyRecognizer()
    heard: List[int] = []

    def probability(audio: np.ndarray) -> float:
        heard.append(audio.size)
        return 0.25

    recognize = Recognition(48000, SpeechScreen(0.0, 0.5, probability), Stopwatch())
    assert recognize(np.zeros(48000, dtype=np.float32), engine) == RecognitionOutcome(
        discard=Discard.BELOW_VAD_THRESHOLD
    )
    assert heard == [16000]
    assert engine.utterances == []


def test_an_engine_failure_is_the_outcome_not_an_exception() -> None:
    engine = FailingRecognizer()
    outcome = Recognition(16000, NO_SCREEN, Stopwatch(1.0, 2.0))(np.zeros(160, dtype=np.float32), engine)
    assert isinstance(outcome.error, RuntimeError)
    assert str(outcome.error) == "engine fell over"
    assert (outcome.answer, outcome.discard, outcome.took) == (None, None, 1.0)  # the engine's time


def test_system_exit_from_an_engine_is_a_failure_like_any_other() -> None:
    outcome = Recognition(16000, NO_SCREEN, Stopwatch(1.0, 2.0))(
        np.zeros(160, dtype=np.float32), ExitingRecognizer()
    )
    assert isinstance(outcome.error, SystemExit)
    assert outcome.error.code == 3


def test_a_failing_screen_is_a_failure_too() -> None:
    def probability(audio: np.ndarray) -> float:
        raise ValueError("no model")

    engine = SpyRecognizer()
    outcome = Recognition(16000, SpeechScreen(0.0, 0.5, probability), Stopwatch())(
        np.zeros(16000, dtype=np.float32), engine
    )
    assert isinstance(outcome.error, ValueError)
    assert str(outcome.error) == "no model"
    assert engine.utterances == []


def test_the_engine_after_a_failure_is_used_again() -> None:
    engine = FailingRecognizer()
    recognize = Recognition(16000, NO_SCREEN, Stopwatch(0.0, 0.25, 1.0, 1.5))
    assert recognize(np.zeros(160, dtype=np.float32), engine).error is not None
    assert recognize(np.zeros(160, dtype=np.float32), engine) == RecognitionOutcome(HEARD, took=0.5)


def test_a_stopped_recognition_still_says_how_long_the_engine_ran() -> None:
    now = [10.0]
    engine = StoppedRecognizer(now)
    outcome = Recognition(16000, NO_SCREEN, lambda: now[0])(np.zeros(160, dtype=np.float32), engine)
    assert isinstance(outcome.error, RuntimeError)
    assert outcome.took == 0.75
