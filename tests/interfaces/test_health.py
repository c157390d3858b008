"""The periodic checks alone (speech_event/interfaces/health.py): soundDetection, /diagnostics, the heartbeat."""

import dataclasses
import logging
from typing import Dict, List, Optional, Tuple

import pytest

from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus, MemoryPublisher
from speech_event.config import SpeechEventConfig
from speech_event.interfaces.diagnostics import DIAGNOSTICS_TOPIC, STATUS_NAME, NodeState, NodeStatistics
from speech_event.interfaces.health import Health
from speech_event.messages import DiagnosticArray, DiagnosticStatus, Float32MultiArray, KeyValue
from speech_event.pipeline.screen import Discard
from speech_event.ports import PublisherStatus
from speech_event.topics import SIGNAL_TOPIC

CONFIG = SpeechEventConfig(health_check_period=5.0, heartbeat_msg_period=10.0, verbose_mode=False)
VERBOSE = dataclasses.replace(CONFIG, verbose_mode=True)
DISCARDS = [reason.value for reason in Discard]  # what the node tells Health


class Rig:
    """Health on the in-memory bus with a fake clock; what it published and said."""

    def __init__(
        self, config: SpeechEventConfig, sound_detection_up: bool = True, start: float = 0.0
    ) -> None:
        self.clock = FakeClock(start)
        self.bus = InMemoryBus()
        self.statistics = NodeStatistics()
        self.downs: List[float] = []
        self.asked: List[PublisherStatus] = []
        self.diagnostics: List[DiagnosticArray] = []
        self.bus.subscribe(DIAGNOSTICS_TOPIC, DiagnosticArray, self._diagnostic)
        self.sound_detection: Optional[MemoryPublisher] = None
        if sound_detection_up:
            self.sound_detection = self.bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
        self.rejected: Dict[str, int] = {}
        self.health = Health(config, self.bus, self.clock, self.statistics, self._state, self._down, DISCARDS)

    def _diagnostic(self, message: object) -> None:
        assert isinstance(message, DiagnosticArray)
        self.diagnostics.append(message)

    def _state(self, sound_detection: PublisherStatus) -> NodeState:
        self.asked.append(sound_detection)
        return NodeState(
            engine="SpyRecognizer",
            language="english",
            enabled=True,
            sound_detection=sound_detection,
            rejected=self.rejected,
            clipped=1,
            timed_out=2,
            utterances=3,
            queued_seconds=0.5,
            dropped=4,
        )

    def _down(self) -> None:
        self.downs.append(self.clock.now())

    def levels(self) -> List[Tuple[float, int, str]]:
        return [(array.stamp, array.status[0].level, array.status[0].message) for array in self.diagnostics]


def _values(status: DiagnosticStatus) -> Dict[str, str]:
    return {value.key: value.value for value in status.values}


def _messages(caplog: pytest.LogCaptureFixture) -> List[Tuple[int, str]]:
    return [(record.levelno, record.getMessage()) for record in caplog.records]


# -- check ----------------------------------------------------------------------------------------


def test_a_connected_sound_detection_is_up_and_nothing_is_said(caplog: pytest.LogCaptureFixture) -> None:
    rig = Rig(CONFIG)
    with caplog.at_level(logging.INFO, logger="speech_event"):
        rig.health.check()
    assert rig.health.sound_detection is PublisherStatus.CONNECTED
    assert rig.downs == []
    assert caplog.records == []


def test_no_publisher_is_down_and_said_once_a_check(caplog: pytest.LogCaptureFixture) -> None:
    rig = Rig(CONFIG, sound_detection_up=False)
    with caplog.at_level(logging.INFO, logger="speech_event"):
        rig.health.check()
    assert rig.health.sound_detection is PublisherStatus.NONE
    assert rig.downs == [0.0]
    assert _messages(caplog) == [
        (logging.WARNING, "soundDetection is down on /soundDetection/signal: no publisher registered")
    ]


def test_a_crashed_publisher_is_down(caplog: pytest.LogCaptureFixture) -> None:
    rig = Rig(CONFIG)
    assert rig.sound_detection is not None
    rig.sound_detection.crash()
    with caplog.at_level(logging.INFO, logger="speech_event"):
        rig.health.check()
    assert rig.health.sound_detection is PublisherStatus.STALE
    assert rig.downs == [0.0]
    assert _messages(caplog) == [
        (
            logging.WARNING,
            "soundDetection is down on /soundDetection/signal: publisher registered but no live connection",
        )
    ]


def test_a_publisher_that_left_cleanly_is_down() -> None:
    rig = Rig(CONFIG)
    assert rig.sound_detection is not None
    rig.sound_detection.shutdown()
    rig.health.check()
    assert rig.health.sound_detection is PublisherStatus.NONE
    assert rig.downs == [0.0]


def test_before_any_check_sound_detection_is_taken_as_connected() -> None:
    rig = Rig(CONFIG, sound_detection_up=False)
    assert rig.health.sound_detection is PublisherStatus.CONNECTED


# -- the periodic checks and /diagnostics ----------------------------------------------------------


def test_down_is_said_at_every_check_while_it_lasts() -> None:
    rig = Rig(CONFIG, sound_detection_up=False)
    rig.health.start(0.0)
    rig.clock.advance_to(15.0)
    assert rig.downs == [5.0, 10.0, 15.0]


def test_down_is_said_before_the_diagnostics_of_the_same_check() -> None:
    rig = Rig(CONFIG, sound_detection_up=False)
    published_before_down: List[int] = []
    rig.health = Health(
        CONFIG,
        rig.bus,
        rig.clock,
        rig.statistics,
        rig._state,
        lambda: published_before_down.append(len(rig.diagnostics)),
        DISCARDS,
    )
    rig.health.start(0.0)
    rig.clock.advance_to(10.0)
    assert published_before_down == [0, 1]
    assert len(rig.diagnostics) == 2


def _down_then_back(back_at: float, until: float) -> Rig:
    """Checks from time 0 with soundDetection down; it comes back at ``back_at``; run to ``until``."""
    rig = Rig(CONFIG, sound_detection_up=False)
    rig.health.start(0.0)
    rig.clock.advance_to(back_at)
    rig.bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    rig.clock.advance_to(until)
    return rig


def test_sound_detection_coming_back_ends_the_down_calls() -> None:
    rig = _down_then_back(7.5, until=20.0)
    assert rig.downs == [5.0]
    assert rig.health.sound_detection is PublisherStatus.CONNECTED


def test_a_diagnostic_array_is_published_each_period_from_the_start() -> None:
    rig = Rig(CONFIG, start=2.0)
    rig.health.start(2.0)
    rig.clock.advance_to(6.75)
    assert rig.diagnostics == []
    rig.clock.advance_to(12.0)
    assert rig.levels() == [(7.0, DiagnosticStatus.OK, "listening"), (12.0, DiagnosticStatus.OK, "listening")]


def test_the_diagnostic_array_is_the_status_the_check_found() -> None:
    rig = Rig(CONFIG)
    rig.health.start(0.0)
    rig.clock.advance_to(5.0)
    assert len(rig.diagnostics) == 1
    array = rig.diagnostics[0]
    assert array.stamp == 5.0
    assert array.status == (rig.health.status(),)
    status = array.status[0]
    assert (status.name, status.hardware_id) == (STATUS_NAME, "")
    assert status.values[:4] == (
        KeyValue("engine", "SpyRecognizer"),
        KeyValue("language", "english"),
        KeyValue("enabled", "true"),
        KeyValue("soundDetection", "publisher connected"),
    )


def test_the_diagnostics_are_at_error_level_while_sound_detection_is_down() -> None:
    rig = _down_then_back(5.0, until=10.0)
    assert rig.levels() == [
        (5.0, DiagnosticStatus.ERROR, "soundDetection is down: no publisher registered"),
        (10.0, DiagnosticStatus.OK, "listening"),
    ]
    assert _values(rig.diagnostics[0].status[0])["soundDetection"] == "no publisher registered"


def test_the_status_reports_what_the_last_check_found() -> None:
    rig = Rig(CONFIG, sound_detection_up=False)
    rig.health.check()
    assert rig.health.status().level == DiagnosticStatus.ERROR
    assert rig.asked == [PublisherStatus.NONE]


def test_the_status_lists_the_screens_discard_reasons() -> None:
    rig = Rig(CONFIG)
    values = _values(rig.health.status())
    assert [key for key in values if key.startswith("utterances discarded: ")] == [
        "utterances discarded: disabled",
        "utterances discarded: too_short",
        "utterances discarded: below_vad_threshold",
        "utterances discarded: no_speech_after_turn",
        "utterances discarded: backlog",
    ]


def test_stop_ends_the_checks_and_the_diagnostics() -> None:
    rig = Rig(CONFIG, sound_detection_up=False)
    rig.health.start(0.0)
    rig.clock.advance_to(5.0)
    rig.health.stop()
    rig.clock.advance_to(60.0)
    assert rig.downs == [5.0]
    assert [array.stamp for array in rig.diagnostics] == [5.0]


def test_a_failing_check_does_not_stop_the_checks_after_it(caplog: pytest.LogCaptureFixture) -> None:
    rig = Rig(CONFIG, sound_detection_up=False)
    failures = [RuntimeError("the master fell over")]

    def down() -> None:
        if failures:
            raise failures.pop()
        rig.downs.append(rig.clock.now())

    rig.health = Health(CONFIG, rig.bus, rig.clock, rig.statistics, rig._state, down, DISCARDS)
    rig.health.start(0.0)
    with caplog.at_level(logging.ERROR, logger="speech_event"):
        rig.clock.advance_to(10.0)
    assert rig.downs == [10.0]
    assert [array.stamp for array in rig.diagnostics] == [10.0]  # the failed check published none
    assert _messages(caplog) == [(logging.ERROR, "a periodic task failed; it runs again in 5.0 s")]


# -- the heartbeat --------------------------------------------------------------------------------

HEARTBEAT = (
    "speechEvent running: 3 utterances so far, rejected messages {'empty': 2}, clipped messages 1, "
    "0.5 s of speech waiting for recognition, 4 dropped (max_backlog), 2 timed out"
)


def test_the_heartbeat_line_says_what_the_node_has_done(caplog: pytest.LogCaptureFixture) -> None:
    rig = Rig(VERBOSE)
    rig.rejected = {"empty": 2, "not_finite": 0}
    with caplog.at_level(logging.INFO, logger="speech_event"):
        rig.health.heartbeat()
    assert _messages(caplog) == [(logging.INFO, HEARTBEAT)]


def test_in_verbose_mode_the_heartbeat_beats_every_heartbeat_msg_period(
    caplog: pytest.LogCaptureFixture,
) -> None:
    rig = Rig(VERBOSE)
    rig.rejected = {"empty": 2}
    rig.health.start(0.0)
    with caplog.at_level(logging.INFO, logger="speech_event"):
        rig.clock.advance_to(9.75)
        assert caplog.records == []
        rig.clock.advance_to(20.0)
    assert _messages(caplog) == [(logging.INFO, HEARTBEAT), (logging.INFO, HEARTBEAT)]


def test_no_heartbeat_outside_verbose_mode(caplog: pytest.LogCaptureFixture) -> None:
    rig = Rig(CONFIG)
    rig.health.start(0.0)
    with caplog.at_level(logging.INFO, logger="speech_event"):
        rig.clock.advance_to(60.0)
    assert caplog.records == []
    assert len(rig.diagnostics) == 12


def test_no_heartbeat_with_heartbeat_msg_period_0(caplog: pytest.LogCaptureFixture) -> None:
    rig = Rig(dataclasses.replace(VERBOSE, heartbeat_msg_period=0.0))
    rig.health.start(0.0)
    with caplog.at_level(logging.INFO, logger="speech_event"):
        rig.clock.advance_to(60.0)
    assert caplog.records == []


def test_stop_ends_the_heartbeat(caplog: pytest.LogCaptureFixture) -> None:
    rig = Rig(VERBOSE)
    rig.health.start(0.0)
    rig.health.stop()
    with caplog.at_level(logging.INFO, logger="speech_event"):
        rig.clock.advance_to(60.0)
    assert caplog.records == []
