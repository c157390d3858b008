import logging
from typing import Callable, Dict, List

import numpy as np
import pytest

from fixtures.audio import speak_tones
from fixtures.fakes import FailingRecognizer, GatedRecognizer, SpyRecognizer
from fixtures.rig import AT_16K, Rig
from harness.memory_runner import run_in_memory
from harness.scenario import Say, Scenario, Silence
from speech_event import SIGNAL_TOPIC
from speech_event.adapters.executors import ClockExecutor, ThreadExecutor
from speech_event.adapters.fake_clock import FakeClock, FakeTimer
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.config import SpeechEventConfig, apply_overrides
from speech_event.messages import Float32MultiArray
from speech_event.node import SpeechEventNode
from speech_event.pipeline.resample import resample
from speech_event.ports import Transcript
from speech_event.recognizers.tones import ToneRecognizer


def test_speech_that_arrives_while_a_slow_recognition_runs_is_kept_and_published_in_order() -> None:
    scenario = Scenario(
        name="slow",
        source="test",
        # Without speculation: each recognition starts when its utterance closes (with it they
        # come sooner: tests/turns/test_speculation.py).
        config=SpeechEventConfig(speculative_recognition=False),
        steps=(Say("one"), Silence(1.6), Say("two"), Silence(1.6), Say("three")),
        expected=("one", "two", "three"),
    )
    fast = run_in_memory(scenario).published
    slow = run_in_memory(scenario, recognition_seconds=3.0).published
    assert [m.text for m in slow] == [m.text for m in fast] == ["one", "two", "three"]
    # One worker: each result comes 3 s after its utterance closed or after the previous result.
    assert slow[0].time == pytest.approx(fast[0].time + 3.0)
    for before, after in zip(slow, slow[1:]):
        assert after.time >= before.time + 3.0 - 1e-9


def test_with_a_worker_thread_the_callback_never_waits_for_recognition() -> None:
    recognizer = GatedRecognizer()
    executor = ThreadExecutor()
    rig = Rig(AT_16K, recognizer, executor)
    first = np.full(8000, 0.1, dtype=np.float32)
    second = np.full(12000, 0.2, dtype=np.float32)
    rig.speak(first)
    rig.clock.advance(2.0)  # the pause ends the first utterance: its recognition starts and blocks
    assert recognizer.started.wait(10)
    rig.speak(second)  # every callback returns while the recognition is still blocked
    assert not recognizer.gate.is_set()
    assert rig.node.pending_samples == second.size
    rig.clock.advance(2.0)
    recognizer.gate.set()
    assert executor.shutdown(timeout=10)
    assert [u.size for u in recognizer.utterances] == [first.size, second.size]
    assert rig.texts() == ["heard", "heard"]


def test_health_checks_run_at_multiples_of_the_period_and_report_every_check_that_finds_it_down() -> None:
    rig = Rig(SpeechEventConfig(health_check_period=2.0), SpyRecognizer())
    rig.clock.advance_to(3.0)
    rig.sound_detection.crash()
    rig.clock.advance_to(7.0)
    rig.bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    rig.clock.advance_to(9.0)
    rig.bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection").shutdown()
    rig.clock.advance_to(10.0)
    assert rig.published == [
        (4.0, "Error: soundDetection is down"),
        (6.0, "Error: soundDetection is down"),
        (10.0, "Error: soundDetection is down"),
    ]


@pytest.mark.parametrize(
    ("transcript", "overrides", "expected"),
    [
        (Transcript("  go left \n"), {}, ["go left"]),
        (Transcript("   "), {}, []),
        (Transcript(""), {"publish_unrecognized": True}, ["Error: speech not recognized"]),
        (Transcript("go", confidence=0.3), {"confidence": 0.5}, []),
        (
            Transcript("go", confidence=0.3),
            {"confidence": 0.5, "publish_unrecognized": True},
            ["Error: speech not recognized"],
        ),
        (Transcript("go", confidence=0.5), {"confidence": 0.5}, ["go"]),
    ],
)
def test_what_is_published_for_a_transcript(
    transcript: Transcript, overrides: Dict[str, object], expected: List[str]
) -> None:
    config = apply_overrides(SpeechEventConfig(sample_rate=16000), overrides, "test")
    rig = Rig(config, SpyRecognizer(transcript))
    rig.speak(np.full(4096, 0.1, dtype=np.float32))
    rig.clock.advance(2.0)
    assert rig.texts() == expected


def test_a_failing_recognition_is_logged_and_the_node_goes_on(caplog: pytest.LogCaptureFixture) -> None:
    rig = Rig(AT_16K, FailingRecognizer())
    with caplog.at_level(logging.ERROR, logger="speech_event"):
        rig.speak(np.full(4000, 0.1, dtype=np.float32))
        rig.clock.advance(2.0)
        rig.speak(np.full(4000, 0.1, dtype=np.float32))
        rig.clock.advance(2.0)
    assert rig.texts() == ["heard"]
    assert [r.getMessage() for r in caplog.records] == ["recognition of utterance 1 (0.25 s) failed"]


def test_stop_cancels_the_timers() -> None:
    rig = Rig(SpeechEventConfig(sample_rate=16000, health_check_period=1.0), SpyRecognizer())
    rig.sound_detection.shutdown()
    rig.clock.advance_to(1.5)
    rig.node.stop()
    rig.clock.advance_to(10.0)
    assert rig.published == [(1.0, "Error: soundDetection is down")]


def test_verbose_mode_logs_a_heartbeat(caplog: pytest.LogCaptureFixture) -> None:
    config = SpeechEventConfig(verbose_mode=True, heartbeat_msg_period=2.0, health_check_period=3600.0)
    with caplog.at_level(logging.INFO, logger="speech_event"):
        rig = Rig(config, SpyRecognizer())
        rig.sound_detection.publish(Float32MultiArray(data=[]))
        rig.clock.advance_to(4.5)
    heartbeats = [r.getMessage() for r in caplog.records if "running" in r.getMessage()]
    assert (
        heartbeats
        == [
            "speechEvent running: 0 utterances so far, rejected messages {'empty': 1}, clipped messages 0, "
            "0.0 s of speech waiting for recognition, 0 dropped (max_backlog), 0 timed out",
        ]
        * 2
    )


def test_resampling_removes_what_is_above_the_new_nyquist_and_keeps_speech_band() -> None:
    t = np.arange(48000) / 48000
    above = (0.5 * np.sin(2 * np.pi * 10000 * t)).astype(np.float32)  # 10 kHz: above 8 kHz
    speech_band = (0.5 * np.sin(2 * np.pi * 1000 * t)).astype(np.float32)

    def rms(x: np.ndarray) -> float:
        return float(np.sqrt(np.mean(np.square(x[1000:-1000], dtype=np.float64))))

    assert rms(resample(above, 48000, 16000)) < 1e-3 * rms(above)  # at least 60 dB down, no alias
    assert rms(resample(speech_band, 48000, 16000)) == pytest.approx(rms(speech_band), rel=0.01)
    assert resample(speech_band, 16000, 16000) is speech_band


def test_tones_in_blocks_at_48k_come_out_as_text() -> None:
    rig = Rig(SpeechEventConfig(), ToneRecognizer())
    rig.speak(speak_tones("where is the door", 48000))
    rig.clock.advance(2.0)
    assert rig.texts() == ["where is the door"]


def test_shutdown_abandons_a_recognition_that_outlasts_the_grace_period() -> None:
    recognizer = GatedRecognizer()
    executor = ThreadExecutor()

    def recognize() -> None:
        recognizer.transcribe(np.zeros(1, dtype=np.float32))

    executor.submit(recognize)
    assert recognizer.started.wait(10)
    assert executor.shutdown(timeout=0.1) is False  # still running: abandoned (a daemon thread)
    recognizer.gate.set()


def test_a_pause_timer_that_fires_slightly_early_closes_the_utterance_once() -> None:
    class EarlyClock(FakeClock):
        """Fires every timer 0.5 ms early, as a clock with rounding might."""

        timers_set = 0

        def call_at(self, when: float, callback: Callable[[], None]) -> FakeTimer:
            self.timers_set += 1
            if self.timers_set > 20:  # the node re-arms the same timer again and again: it would spin
                raise RuntimeError("a timer was set again and again at the same instant")
            return super().call_at(when - 0.0005, callback)

    clock, bus = EarlyClock(), InMemoryBus()
    recognizer = SpyRecognizer()
    node = SpeechEventNode(AT_16K, bus, clock, recognizer, ClockExecutor(clock))
    sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    node.start()
    sound_detection.publish(Float32MultiArray(data=np.full(4096, 0.1, dtype=np.float32)))
    clock.advance_to(1.4999)  # the pause (1.5 s) fired early at 1.4995: that is due
    assert [u.size for u in recognizer.utterances] == [4096]
