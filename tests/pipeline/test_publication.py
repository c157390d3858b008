"""Concluding a closed utterance alone (speech_event/pipeline/publication.py): the text published,
the action told, the statistics, and the stored record after publishing."""

import dataclasses
import logging
from pathlib import Path
from typing import Callable, Dict, List, Optional, Tuple

import numpy as np
import pytest

from fixtures.fakes import SpyRecognizer
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus, MemoryGoal
from speech_event.config import SpeechEventConfig
from speech_event.interfaces.action import ListenAction
from speech_event.interfaces.diagnostics import NodeState, NodeStatistics
from speech_event.messages import RecogniseSpeechGoal, RecogniseSpeechResult, String
from speech_event.pipeline.publication import Publication
from speech_event.pipeline.recognition_queue import RecognitionJob, RecognitionOutcome
from speech_event.pipeline.screen import Discard
from speech_event.pipeline.storage import StoredUtterance, UtteranceStore, read_index
from speech_event.ports import PublisherStatus, Transcript
from speech_event.topics import SPEECH_NOT_RECOGNIZED, TEXT_TOPIC

CONFIG = SpeechEventConfig(sample_rate=16000)
UNRECOGNIZED = dataclasses.replace(CONFIG, publish_unrecognized=True)


Describe = Callable[..., StoredUtterance]


class RecordingStore(UtteranceStore):
    """Keeps what it is handed, and what had been published on the text topic by then."""

    def __init__(self) -> None:  # no folder, no writer thread
        self.published: Callable[[], List[str]] = list
        self.saved: List[Tuple[int, float, int, StoredUtterance, List[str]]] = []

    def save(self, number: int, started_at: float, audio: np.ndarray, describe: Describe) -> None:
        line = describe(file="utterance.wav", start_time=started_at, duration=audio.size / 16000)
        self.saved.append((number, started_at, audio.size, line, self.published()))


class Rig:
    """Publication on the in-memory bus, with an action that has a goal listening since time 0."""

    def __init__(self, config: SpeechEventConfig = CONFIG, store: Optional[UtteranceStore] = None) -> None:
        self.clock = FakeClock()
        self.bus = InMemoryBus()
        self.published: List[str] = []
        self.bus.subscribe(TEXT_TOPIC, String, self._text)
        self.statistics = NodeStatistics()
        self.action = ListenAction(self.clock, lambda: None)
        self.store = store
        self.publication = Publication(config, self.statistics, self.action, store, self.clock.now)
        self.goal = MemoryGoal(RecogniseSpeechGoal(wait=10.0), lambda goal: None)
        self.action.on_goal(self.goal)

    def _text(self, message: object) -> None:
        assert isinstance(message, String)
        self.published.append(message.data)

    def start(self) -> "Rig":
        self.publication.start(self.bus)
        return self

    def conclude(self, outcome: RecognitionOutcome, number: int = 1) -> RecognitionJob:
        """Utterance ``number`` (0.5 s, started at 1.0 s) closed and was recognized: ``outcome``."""
        job = RecognitionJob(
            number, 1.0, 1.5, 1.25, np.zeros(8000, dtype=np.float32), SpyRecognizer(), "english", 0.5
        )
        self.statistics.queued(job.seconds)
        self.action.utterance_closed(number, job.started_at, more_follows=False)
        self.publication.conclude(job, outcome)
        return job

    def values(self) -> Dict[str, str]:
        state = NodeState("SpyRecognizer", "english", True, PublisherStatus.CONNECTED, {})
        status = self.statistics.status(state, [reason.value for reason in Discard])
        return {value.key: value.value for value in status.values}


def _said(text: str, confidence: Optional[float] = None, took: float = 0.25) -> RecognitionOutcome:
    return RecognitionOutcome(Transcript(text, confidence), took=took)


def _messages(caplog: pytest.LogCaptureFixture) -> List[Tuple[int, str]]:
    return [(record.levelno, record.getMessage()) for record in caplog.records]


def _stored(file: str, transcript: str, recognition_time: float) -> StoredUtterance:
    """The index line of the utterance Rig.conclude closes, published as "go left"."""
    return StoredUtterance(
        file=file,
        start_time=1.0,
        duration=0.5,
        language="english",
        engine="SpyRecognizer",
        transcript=transcript,
        published="go left",
        recognition_time=recognition_time,
    )


# -- publish --------------------------------------------------------------------------------------


def test_publish_before_start_publishes_nothing() -> None:
    rig = Rig()
    rig.publication.publish_error("hello", "english", "SpyRecognizer")
    assert rig.published == []


def test_publish_after_start_publishes_the_text_as_it_is() -> None:
    rig = Rig().start()
    rig.publication.publish_error(" Error: soundDetection is down ", "english", "SpyRecognizer")
    assert rig.published == [" Error: soundDetection is down "]


# -- conclude: the text ---------------------------------------------------------------------------


def test_a_transcript_is_published_stripped() -> None:
    rig = Rig().start()
    rig.conclude(_said("  go left "))
    assert rig.published == ["go left"]


def test_the_conclusion_is_logged_with_the_transcript_and_the_text(caplog: pytest.LogCaptureFixture) -> None:
    rig = Rig().start()
    with caplog.at_level(logging.INFO, logger="speech_event"):
        rig.conclude(_said("  go left ", took=0.25), number=4)
    assert _messages(caplog) == [(logging.INFO, "utterance 4 (0.50 s): '  go left ' -> 'go left'")]


def test_an_empty_transcript_publishes_nothing() -> None:
    rig = Rig().start()
    rig.conclude(_said("   "))
    assert rig.published == []


def test_an_empty_transcript_publishes_the_error_text_with_publish_unrecognized() -> None:
    rig = Rig(UNRECOGNIZED).start()
    rig.conclude(_said(""))
    assert rig.published == [SPEECH_NOT_RECOGNIZED]
    assert SPEECH_NOT_RECOGNIZED == "Error: speech not recognized"


def test_a_transcript_below_the_confidence_threshold_publishes_nothing() -> None:
    rig = Rig(dataclasses.replace(CONFIG, confidence=0.5)).start()
    rig.conclude(_said("go left", confidence=0.25))
    rig.conclude(_said("go right", confidence=0.5), number=2)
    assert rig.published == ["go right"]


def test_a_discarded_utterance_publishes_nothing_even_with_publish_unrecognized(
    caplog: pytest.LogCaptureFixture,
) -> None:
    rig = Rig(UNRECOGNIZED).start()
    with caplog.at_level(logging.INFO, logger="speech_event"):
        rig.conclude(RecognitionOutcome(discard=Discard.TOO_SHORT), number=2)
    assert rig.published == []
    assert _messages(caplog) == [(logging.INFO, "utterance 2 (0.50 s) is not transcribed: too_short")]


def test_a_failed_recognition_is_logged_with_its_exception_and_publishes_nothing(
    caplog: pytest.LogCaptureFixture,
) -> None:
    rig = Rig().start()
    problem = RuntimeError("engine fell over")
    with caplog.at_level(logging.ERROR, logger="speech_event"):
        rig.conclude(RecognitionOutcome(error=problem), number=3)
    assert rig.published == []
    assert _messages(caplog) == [(logging.ERROR, "recognition of utterance 3 (0.50 s) failed")]
    assert caplog.records[0].exc_info is not None
    assert caplog.records[0].exc_info[1] is problem


def test_a_failed_recognition_publishes_the_error_text_with_publish_unrecognized() -> None:
    rig = Rig(UNRECOGNIZED).start()
    rig.conclude(RecognitionOutcome(error=SystemExit(1)))
    assert rig.published == [SPEECH_NOT_RECOGNIZED]


def test_an_answer_that_is_not_a_transcript_is_a_failed_recognition(caplog: pytest.LogCaptureFixture) -> None:
    rig = Rig().start()
    with caplog.at_level(logging.ERROR, logger="speech_event"):
        rig.conclude(RecognitionOutcome(answer="go left"))
    assert rig.published == []
    assert _messages(caplog) == [(logging.ERROR, "recognition of utterance 1 (0.50 s) failed")]


def test_a_confidence_out_of_range_is_a_failed_recognition() -> None:
    rig = Rig().start()
    rig.conclude(_said("go left", confidence=1.5))
    assert rig.published == []


def test_nothing_is_published_before_start_but_the_action_is_told() -> None:
    rig = Rig()
    rig.conclude(_said("go left"))
    assert rig.published == []
    assert (rig.goal.state, rig.goal.result) == ("succeeded", RecogniseSpeechResult("go left"))


# -- conclude: the statistics ---------------------------------------------------------------------


def test_a_published_transcript_is_counted_transcribed_and_published() -> None:
    rig = Rig().start()
    rig.conclude(_said("go left", took=0.25))
    values = rig.values()
    assert (values["utterances transcribed"], values["texts published"]) == ("1", "1")
    assert values["last recognition time (s)"] == "0.2500"
    assert values["last real-time factor"] == "0.5000"
    assert (values["utterances waiting for recognition"], values["queued audio (s)"]) == ("0", "0.000")


def test_a_transcript_not_published_is_counted_transcribed_only() -> None:
    rig = Rig().start()
    rig.conclude(_said(""))
    values = rig.values()
    assert (values["utterances transcribed"], values["texts published"]) == ("1", "0")


def test_a_discarded_utterance_is_counted_by_its_reason_and_not_transcribed() -> None:
    rig = Rig().start()
    rig.conclude(RecognitionOutcome(discard=Discard.BELOW_VAD_THRESHOLD))
    values = rig.values()
    assert values["utterances discarded: below_vad_threshold"] == "1"
    assert values["utterances discarded: too_short"] == "0"
    assert values["utterances transcribed"] == "0"
    assert values["utterances waiting for recognition"] == "0"


def test_a_failed_recognition_is_not_counted_transcribed_but_is_no_longer_waiting() -> None:
    rig = Rig().start()
    rig.conclude(RecognitionOutcome(error=RuntimeError("engine fell over")))
    values = rig.values()
    assert (values["utterances transcribed"], values["texts published"]) == ("0", "0")
    assert values["utterances waiting for recognition"] == "0"


def test_an_answer_that_is_not_a_transcript_counts_as_transcribed() -> None:
    """The engine ran and answered, so its time is in the figures, though the answer is refused."""
    rig = Rig().start()
    rig.conclude(RecognitionOutcome(answer=None, took=0.25))
    values = rig.values()
    assert (values["utterances transcribed"], values["texts published"]) == ("1", "0")


# -- conclude: the action -------------------------------------------------------------------------


def test_the_action_gets_the_published_text() -> None:
    rig = Rig().start()
    rig.conclude(_said(" go left "))
    assert (rig.goal.state, rig.goal.result) == ("succeeded", RecogniseSpeechResult("go left"))


def test_the_action_gets_the_error_text_when_it_is_published() -> None:
    rig = Rig(UNRECOGNIZED).start()
    rig.conclude(_said(""))
    assert rig.goal.result == RecogniseSpeechResult(SPEECH_NOT_RECOGNIZED)


def test_the_action_gets_an_empty_text_when_nothing_is_published() -> None:
    rig = Rig().start()
    rig.conclude(RecognitionOutcome(error=RuntimeError("engine fell over")))
    assert (rig.goal.state, rig.goal.result) == ("succeeded", RecogniseSpeechResult(""))


def test_a_discarded_utterance_leaves_the_action_listening() -> None:
    rig = Rig().start()
    rig.conclude(RecognitionOutcome(discard=Discard.TOO_SHORT))
    assert (rig.goal.state, rig.goal.result) == ("active", None)
    rig.conclude(_said("go left"), number=2)
    assert (rig.goal.state, rig.goal.result) == ("succeeded", RecogniseSpeechResult("go left"))


# -- conclude: storage ----------------------------------------------------------------------------


def test_storage_is_handed_the_utterance_after_it_is_published() -> None:
    store = RecordingStore()
    rig = Rig(store=store).start()
    store.published = lambda: list(rig.published)
    rig.conclude(_said(" go left ", took=0.1234567), number=5)
    assert store.saved == [
        (
            5,
            1.0,
            8000,
            _stored("utterance.wav", " go left ", recognition_time=0.123457),
            ["go left"],  # what the text topic had when the store was called
        )
    ]


def test_a_discarded_utterance_is_stored_with_nothing_published() -> None:
    store = RecordingStore()
    rig = Rig(store=store).start()
    rig.conclude(RecognitionOutcome(discard=Discard.TOO_SHORT))
    line = store.saved[0][3]
    assert (line.transcript, line.published, line.recognition_time) == ("", None, 0.0)


def test_a_failed_recognition_is_stored_with_an_empty_transcript() -> None:
    store = RecordingStore()
    rig = Rig(UNRECOGNIZED, store=store).start()
    rig.conclude(RecognitionOutcome(error=RuntimeError("engine fell over")))
    line = store.saved[0][3]
    assert (line.transcript, line.published) == ("", SPEECH_NOT_RECOGNIZED)


def test_the_real_store_writes_the_index_line(tmp_path: Path) -> None:
    store = UtteranceStore(str(tmp_path), 16000, 500.0)
    try:
        rig = Rig(store=store).start()
        rig.conclude(_said("go left", took=0.25), number=2)
        store.flush()
    finally:
        store.close()
    assert rig.published == ["go left"]
    assert read_index(tmp_path) == [
        _stored("19700101-000001.000_000002.wav", "go left", recognition_time=0.25)
    ]
    assert (tmp_path / "19700101-000001.000_000002.wav").is_file()
