"""/diagnostics: one status named for the node, at every health check, with what it has done."""

import itertools

import numpy as np

from fixtures.audio import speak_tones
from fixtures.fakes import SpyRecognizer
from fixtures.rig import Rig
from speech_event.config import SpeechEventConfig
from speech_event.interfaces.services import SET_ENABLED_SERVICE
from speech_event.messages import DiagnosticArray, DiagnosticStatus, Float32MultiArray, SetEnabledRequest
from speech_event.recognizers.tones import ToneRecognizer

CONFIG = SpeechEventConfig(sample_rate=16000, health_check_period=2.0, min_utterance_length=0.3)


def _values(array: DiagnosticArray) -> dict:  # type: ignore[type-arg]
    (status,) = array.status
    return {value.key: value.value for value in status.values}


def test_the_status_counts_what_the_node_did_and_times_recognition() -> None:
    ticks = itertools.count(0.0, 0.25)  # each recognition takes 0.25 s on this stopwatch
    rig = Rig(CONFIG, SpyRecognizer(), stopwatch=lambda: next(ticks))
    rig.sound_detection.publish(Float32MultiArray(data=[]))  # rejected: empty
    rig.speak(np.full(8000, 0.1, dtype=np.float32))  # 0.5 s, transcribed in 0.25 s
    rig.clock.advance_to(2.5)
    rig.speak(np.full(1000, 0.1, dtype=np.float32))  # too short
    rig.clock.advance_to(4.5)
    rig.speak(np.full(4096, 0.1, dtype=np.float32))
    rig.bus.call(SET_ENABLED_SERVICE, SetEnabledRequest("false"))  # drops the utterance being collected
    rig.sound_detection.publish(Float32MultiArray(data=np.zeros(10, np.float32)))  # ignored
    rig.clock.advance_to(6.0)
    assert [array.stamp for array in rig.diagnostics] == [2.0, 4.0, 6.0]
    (status,) = rig.diagnostics[-1].status
    assert (status.level, status.name, status.message) == (DiagnosticStatus.OK, "speechEvent", "disabled")
    assert _values(rig.diagnostics[-1]) == {
        "engine": "SpyRecognizer",
        "language": "english",
        "enabled": "false",
        "soundDetection": "publisher connected",
        "utterances transcribed": "1",
        "texts published": "1",
        "grammar": "none (free speech)",
        "utterances out of grammar": "0",
        "utterances discarded: disabled": "1",
        "utterances discarded: too_short": "1",
        "utterances discarded: below_vad_threshold": "0",
        "utterances discarded: no_speech_after_turn": "0",
        "utterances discarded: backlog": "0",
        "messages ignored while disabled": "1",
        "rejected messages: empty": "1",
        "rejected messages: nan_or_inf": "0",
        "rejected messages: out_of_range": "0",
        "rejected messages: multi_dimensional": "0",
        "rejected messages: oversized": "0",
        "rejected messages: wrong_type": "0",
        "rejected messages: malformed": "0",
        "clipped messages": "0",
        "last recognition time (s)": "0.2500",
        "mean recognition time (s)": "0.2500",
        "last real-time factor": "0.5000",
        "mean real-time factor": "0.5000",
        "utterances waiting for recognition": "0",
        "queued audio (s)": "0.000",
        "recognitions timed out": "0",
        "partial results published": "0",
        "partial results worker time (s)": "0.000",
    }


def test_sound_detection_down_is_an_error_and_a_backlog_a_warning() -> None:
    rig = Rig(CONFIG, SpyRecognizer(), job_seconds=10.0)
    for _ in range(3):  # three utterances closed by 5.5 s, each recognized in 10 s of clock
        rig.speak(np.full(4096, 0.1, dtype=np.float32))
        rig.clock.advance(1.6)
    rig.clock.advance_to(6.0)
    rig.sound_detection.shutdown()
    rig.clock.advance_to(8.0)
    levels = [(array.stamp, array.status[0].level, array.status[0].message) for array in rig.diagnostics]
    assert levels == [
        (2.0, DiagnosticStatus.OK, "listening"),
        (4.0, DiagnosticStatus.WARN, "recognition backlog: 1 utterances wait behind the running one"),
        (6.0, DiagnosticStatus.WARN, "recognition backlog: 2 utterances wait behind the running one"),
        (8.0, DiagnosticStatus.ERROR, "soundDetection is down: no publisher registered"),
    ]
    assert _values(rig.diagnostics[-1])["queued audio (s)"] == "0.768"  # 3 x 4096 samples
    assert _values(rig.diagnostics[0])["last recognition time (s)"] == "none yet"


def test_the_status_counts_partial_results_and_the_engine_time_they_took() -> None:
    ticks = itertools.count(0.0, 0.125)  # each run, partial or not, takes 0.125 s on this stopwatch
    rig = Rig(CONFIG, ToneRecognizer(), stopwatch=lambda: next(ticks))
    rig.speak(speak_tones("go to the kitchen", 16000))  # partials at 0.756 and 1.256 s (test_partials)
    rig.clock.advance_to(4.0)
    values = _values(rig.diagnostics[-1])
    assert (values["partial results published"], values["partial results worker time (s)"]) == ("2", "0.250")
    assert values["texts published"] == "1"
