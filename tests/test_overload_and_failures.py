"""Recognizers that answer nonsense, fail hard, hang or cannot keep up: handled, bounded, visible."""

import dataclasses
import logging
import threading
from typing import List

import numpy as np
import pytest

from fixtures.fakes import SpyRecognizer
from fixtures.rig import Rig
from speech_event.adapters.executors import ThreadExecutor
from speech_event.config import SpeechEventConfig
from speech_event.messages import String
from speech_event.ports import Transcript
from speech_event.topics import PARTIAL_TOPIC

HALF_SECOND = np.full(8000, 0.1, dtype=np.float32)
UNRECOGNIZED = SpeechEventConfig(sample_rate=16000, health_check_period=3600.0, publish_unrecognized=True)


class Answering(SpyRecognizer):
    """Answers with whatever the test gives it, proper transcript or not."""

    def __init__(self, answer: object) -> None:
        super().__init__()
        self.raw = answer

    def transcribe(self, audio: np.ndarray) -> Transcript:
        super().transcribe(audio)
        return self.raw  # type: ignore[return-value]


@pytest.mark.parametrize(
    ("answer", "problem"),
    [
        (None, "the engine answered None, not a Transcript with text"),
        ("go left", "the engine answered 'go left', not a Transcript with text"),
        (
            Transcript(5),  # type: ignore[arg-type]
            "the engine answered Transcript(text=5, confidence=None, rejected=None), not a Transcript with text",
        ),
        (Transcript("go", 1.5), "the engine reported confidence 1.5; allowed: a number from 0 to 1 or none"),
        (
            Transcript("go", -0.1),
            "the engine reported confidence -0.1; allowed: a number from 0 to 1 or none",
        ),
        (
            Transcript("go", "high"),  # type: ignore[arg-type]
            "the engine reported confidence 'high'; allowed: a number from 0 to 1 or none",
        ),
    ],
)
def test_an_answer_that_is_no_proper_transcript_is_logged_as_not_recognized(
    answer: object, problem: str, caplog: pytest.LogCaptureFixture
) -> None:
    rig = Rig(UNRECOGNIZED, Answering(answer))
    with caplog.at_level(logging.ERROR, logger="speech_event"):
        rig.speak(HALF_SECOND)
        rig.clock.advance(2.0)
    assert rig.texts() == ["Error: speech not recognized"]
    (record,) = caplog.records
    assert record.getMessage() == "recognition of utterance 1 (0.50 s) failed"
    assert str(record.exc_info[1]) == problem  # type: ignore[index]


def test_a_nan_confidence_counts_as_none_reported_and_the_text_is_published(
    caplog: pytest.LogCaptureFixture,
) -> None:
    config = SpeechEventConfig(sample_rate=16000, health_check_period=3600.0, confidence=0.5)
    rig = Rig(config, Answering(Transcript("go left", float("nan"))))
    with caplog.at_level(logging.WARNING, logger="speech_event"):
        rig.speak(HALF_SECOND)
        rig.clock.advance(2.0)
    assert rig.texts() == ["go left"]
    assert [r.getMessage() for r in caplog.records] == [
        "utterance 1: the engine reported confidence NaN; taken as no confidence reported"
    ]


class StoppableAnswering(Answering):
    """Answers as Answering does, and can be stopped: the node speculates and asks it for partial
    texts."""

    def stop(self) -> None:
        pass


@pytest.mark.parametrize(
    "answer",
    [
        None,
        Transcript(None),  # type: ignore[arg-type]
        Transcript(5),  # type: ignore[arg-type]
        # "yes" is a complete answer, so a speculation taking it ends the turn early.
        Transcript("yes", 1.5),
        Transcript("yes", "high"),  # type: ignore[arg-type]
    ],
)
def test_a_speculation_takes_an_answer_that_is_no_proper_transcript_as_the_final_recognition_does(
    answer: object, caplog: pytest.LogCaptureFixture
) -> None:
    """A failed recognition: no complete answer (the whole pause is waited for), no partial text,
    no exception in the speculation's job; the final recognition adopts it and says why it failed."""
    rig = Rig(dataclasses.replace(UNRECOGNIZED, early_pause=0.5), StoppableAnswering(answer))
    partials: List[str] = []
    rig.bus.subscribe(PARTIAL_TOPIC, String, lambda message: partials.append(message.data))  # type: ignore[attr-defined]
    with caplog.at_level(logging.WARNING, logger="speech_event"):
        rig.speak(HALF_SECOND)  # its last block at 0.512 s
        rig.clock.advance(2.0)
    assert [(round(time, 3), text) for time, text in rig.published] == [
        (2.012, "Error: speech not recognized")
    ]
    assert partials == []
    assert (rig.node.speculations.started, rig.node.speculations.used) == (1, 1)
    (record,) = caplog.records
    assert record.getMessage() == "recognition of utterance 1 (0.50 s) failed"


class Exiting(SpyRecognizer):
    """Raises SystemExit on its first utterance, then a BaseException of its own, then works."""

    class Odd(BaseException):
        pass

    def transcribe(self, audio: np.ndarray) -> Transcript:
        super().transcribe(audio)
        if len(self.utterances) == 1:
            raise SystemExit(3)
        if len(self.utterances) == 2:
            raise Exiting.Odd("odd")
        return Transcript("heard")


def test_system_exit_or_another_base_exception_never_kills_the_recognition_worker(
    caplog: pytest.LogCaptureFixture,
) -> None:
    executor = ThreadExecutor()
    rig = Rig(UNRECOGNIZED, Exiting(), executor=executor)
    with caplog.at_level(logging.ERROR, logger="speech_event"):
        for _ in range(3):
            rig.speak(HALF_SECOND)
            rig.clock.advance(2.0)
        assert executor.shutdown(timeout=10)
    # SystemExit is a failed recognition; the odd BaseException escapes the node, not the worker
    assert rig.texts() == ["Error: speech not recognized", "heard"]
    assert [r.getMessage() for r in caplog.records] == [
        "recognition of utterance 1 (0.50 s) failed",
        "a recognition job failed; the recognition worker goes on",
    ]


def test_the_queue_never_holds_more_than_max_backlog_and_the_oldest_are_dropped(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """A recognizer that never catches up: each recognition takes 1000 s of clock. (Without
    speculation, so the figures are the queue's alone: a speculation starts the first recognition
    a little earlier.)"""
    config = SpeechEventConfig(
        sample_rate=16000, health_check_period=3600.0, max_backlog=10.0, speculative_recognition=False
    )
    recognizer = SpyRecognizer()
    rig = Rig(config, recognizer, job_seconds=1000.0)
    queued: List[float] = []
    with caplog.at_level(logging.WARNING, logger="speech_event"):
        for number in range(100):  # 100 utterances of 0.5 s, each 16 samples longer than the last
            rig.speak(np.full(8000 + 16 * number, 0.1, dtype=np.float32), block=8000 + 16 * number)
            rig.clock.advance(1.6)
            queued.append(rig.node.queued_speech_seconds)
    assert max(queued) <= 10.0
    messages = [r.getMessage() for r in caplog.records]
    assert messages[0] == (
        "recognition is falling behind: 5.0 s of speech waits (max_backlog 10 s; past it the oldest "
        "utterance is dropped)"
    )
    assert messages[1] == (
        "dropped utterance 1 (0.50 s) unrecognized: 10.2 s of speech waited, more than max_backlog 10 s"
    )
    dropped = [m for m in messages if m.startswith("dropped utterance")]
    rig.clock.advance_to(200000.0)
    assert len(recognizer.utterances) + len(dropped) == 100
    # the newest speech is kept: what was recognized is the last utterances, in order
    sizes = [u.size for u in recognizer.utterances]
    assert sizes == [8000 + 16 * n for n in range(100 - len(sizes), 100)]


class Hanging(SpyRecognizer):
    """Hangs until cancelled (then raises, as onnxruntime does when told to terminate)."""

    def __init__(self, cancellable: bool) -> None:
        super().__init__()
        self.started = threading.Event()
        self.release = threading.Event()
        if cancellable:
            self.stop = self.release.set

    def transcribe(self, audio: np.ndarray) -> Transcript:
        super().transcribe(audio)
        if len(self.utterances) == 1:
            self.started.set()
            if not self.release.wait(timeout=30):
                raise TimeoutError("never released")
            if hasattr(self, "stop"):
                raise RuntimeError("Exiting due to terminate flag being set to true")
        return Transcript("heard")


def _hanging_rig(cancellable: bool) -> "tuple[Rig, Hanging, ThreadExecutor]":
    """A node whose first recognition hangs (recognition_timeout 5 s), that recognition started."""
    config = SpeechEventConfig(
        sample_rate=16000,
        health_check_period=3600.0,
        publish_unrecognized=cancellable,
        recognition_timeout=5.0,
    )
    recognizer = Hanging(cancellable)
    executor = ThreadExecutor()
    rig = Rig(config, recognizer, executor=executor)
    rig.speak(HALF_SECOND)
    rig.clock.advance(2.0)
    assert recognizer.started.wait(10)
    return rig, recognizer, executor


def test_a_recognition_past_recognition_timeout_is_logged_cancelled_and_the_node_moves_on(
    caplog: pytest.LogCaptureFixture,
) -> None:
    with caplog.at_level(logging.ERROR, logger="speech_event"):
        rig, _, executor = _hanging_rig(cancellable=True)
        rig.speak(HALF_SECOND)
        rig.clock.advance(5.0)  # the watchdog fires: 5 s after the recognition started
        assert executor.shutdown(timeout=10)
    assert rig.texts() == ["Error: speech not recognized", "heard"]
    assert [r.getMessage() for r in caplog.records] == [
        "recognition of utterance 1 (0.50 s) still runs after recognition_timeout 5 s: cancelling it",
        "recognition of utterance 1 (0.50 s) failed",
    ]


def test_an_engine_that_cannot_be_cancelled_is_named_as_such(caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.ERROR, logger="speech_event"):
        rig, recognizer, executor = _hanging_rig(cancellable=False)
        rig.clock.advance(6.0)
        recognizer.release.set()
        assert executor.shutdown(timeout=10)
    assert [r.getMessage() for r in caplog.records] == [
        "recognition of utterance 1 (0.50 s) still runs after recognition_timeout 5 s: this engine cannot "
        "be cancelled; later utterances wait, bounded by max_backlog"
    ]
    assert rig.texts() == ["heard"]
