"""set_enabled and set_language on the in-memory bus: requests, the node's behaviour, engine switches."""

import logging
import threading
from typing import List

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from fixtures.fakes import Engines, GatedRecognizer, SpyRecognizer
from fixtures.rig import AT_16K, Rig
from speech_event.adapters.executors import ThreadExecutor
from speech_event.config import SpeechEventConfig
from speech_event.interfaces.services import SET_ENABLED_SERVICE, SET_LANGUAGE_SERVICE
from speech_event.messages import SetEnabledRequest, SetLanguageRequest
from speech_event.ports import Transcript

HALF_SECOND = np.full(8000, 0.1, dtype=np.float32)


def _enable(rig: Rig, status: str) -> int:
    return int(rig.bus.call(SET_ENABLED_SERVICE, SetEnabledRequest(status)).response)  # type: ignore[attr-defined]


def _language(rig: Rig, language: str) -> int:
    return int(rig.bus.call(SET_LANGUAGE_SERVICE, SetLanguageRequest(language)).response)  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("status", "response"),
    [("true", 1), ("false", 1), (" TRUE ", 1), ("\tFalse\n", 1), ("yes", 0), ("", 0), ("1", 0), ("truee", 0)],
)
def test_set_enabled_takes_true_or_false_trimmed_in_any_case(status: str, response: int) -> None:
    rig = Rig(AT_16K, SpyRecognizer())
    assert _enable(rig, status) == response
    assert rig.node.enabled is (status.strip().lower() != "false")


def test_a_bad_set_enabled_request_warns_naming_what_is_allowed(caplog: pytest.LogCaptureFixture) -> None:
    rig = Rig(AT_16K, SpyRecognizer())
    with caplog.at_level(logging.WARNING, logger="speech_event"):
        assert _enable(rig, "on") == 0
    assert [r.getMessage() for r in caplog.records] == [
        "/speechEvent/set_enabled: status 'on' is not allowed; allowed: true or false (any case)"
    ]


def test_while_disabled_blocks_are_thrown_away_and_enabling_starts_clean() -> None:
    recognizer = SpyRecognizer()
    rig = Rig(AT_16K, recognizer)
    rig.speak(HALF_SECOND)
    assert _enable(rig, "false") == 1  # the utterance being collected is the robot's own voice
    assert rig.node.pending_samples == 0
    rig.speak(HALF_SECOND)
    rig.clock.advance(2.0)
    assert rig.node.pending_samples == 0
    assert _enable(rig, "true") == 1
    rig.speak(HALF_SECOND[:4096])
    rig.clock.advance(2.0)
    assert [u.size for u in recognizer.utterances] == [4096]
    assert rig.texts() == ["heard"]


def test_health_checks_go_on_while_disabled() -> None:
    rig = Rig(SpeechEventConfig(sample_rate=16000, health_check_period=1.0), SpyRecognizer())
    _enable(rig, "false")
    rig.sound_detection.shutdown()
    rig.clock.advance_to(2.5)
    assert rig.published == [(1.0, "Error: soundDetection is down"), (2.0, "Error: soundDetection is down")]


def test_a_recognition_already_handed_over_still_publishes_after_disabling() -> None:
    rig = Rig(AT_16K, SpyRecognizer(), job_seconds=1.0)
    rig.speak(HALF_SECOND)
    rig.clock.advance(1.6)  # closed at 2.0 s: its recognition ends at 3.0 s
    _enable(rig, "false")
    rig.clock.advance(2.0)
    assert rig.texts() == ["heard"]


@pytest.mark.parametrize("request_text", ["Kinyarwanda", "kinyarwanda", " KINYARWANDA\n"])
def test_set_language_builds_the_other_engine_once_and_later_utterances_use_it(request_text: str) -> None:
    engines = Engines()
    rig = Rig(AT_16K, engines.spies["english"], build_engine=engines.build)
    assert _language(rig, request_text) == 1
    assert rig.node.language == "kinyarwanda"
    rig.speak(HALF_SECOND)
    rig.clock.advance(2.0)
    assert _language(rig, "English") == 1
    assert _language(rig, "Kinyarwanda") == 1
    assert engines.built == ["kinyarwanda"]  # built once, kept for the next switch
    assert rig.texts() == ["kinyarwanda"]


def test_switching_to_the_current_language_answers_1_and_builds_nothing() -> None:
    engines = Engines()
    rig = Rig(AT_16K, engines.spies["english"], build_engine=engines.build)
    assert _language(rig, "English") == 1
    assert engines.built == []


def test_a_language_whose_engine_cannot_be_built_answers_0_and_the_old_one_goes_on(
    caplog: pytest.LogCaptureFixture,
) -> None:
    engines = Engines(failing=("kinyarwanda",))
    rig = Rig(AT_16K, engines.spies["english"], build_engine=engines.build)
    with caplog.at_level(logging.WARNING, logger="speech_event"):
        assert _language(rig, "Kinyarwanda") == 0
        assert _language(rig, "french") == 0
    assert [r.getMessage() for r in caplog.records] == [
        "/speechEvent/set_language: cannot switch to kinyarwanda, staying with english: kinyarwanda model is broken",
        "/speechEvent/set_language: language 'french' is not allowed; allowed: english or kinyarwanda (any case)",
    ]
    rig.speak(HALF_SECOND)
    rig.clock.advance(2.0)
    assert rig.texts() == ["english"]


def test_without_an_engine_builder_another_language_answers_0() -> None:
    rig = Rig(AT_16K, SpyRecognizer())
    assert _language(rig, "Kinyarwanda") == 0
    assert rig.node.language == "english"


def test_an_utterance_closed_before_the_switch_finishes_with_the_old_engine() -> None:
    engines = Engines()
    rig = Rig(AT_16K, engines.spies["english"], build_engine=engines.build, job_seconds=1.0)
    rig.speak(HALF_SECOND)
    rig.clock.advance(1.6)  # closed: its recognition runs until 3.0 s
    _language(rig, "kinyarwanda")
    rig.speak(HALF_SECOND)
    rig.clock.advance(4.0)
    assert rig.texts() == ["english", "kinyarwanda"]


@given(st.lists(st.sampled_from(["speak", "close", "switch", "wait"]), max_size=30))
def test_every_utterance_is_transcribed_once_by_the_engine_in_use_when_it_closed(
    operations: List[str],
) -> None:
    """Switches interleaved with utterances and slow recognitions (each takes 0.7 s of clock)."""
    engines = Engines()
    rig = Rig(AT_16K, engines.spies["english"], build_engine=engines.build, job_seconds=0.7)
    expected: List[str] = []
    collecting = False
    last_block = 0.0
    for operation in operations:
        if operation == "speak":
            if collecting and rig.clock.now() + 0.256 >= last_block + 1.5:
                expected.append(rig.node.language)  # the pause ends before the block arrives
            rig.speak(HALF_SECOND[:4096])
            collecting, last_block = True, rig.clock.now()
        elif operation == "switch":
            other = "kinyarwanda" if rig.node.language == "english" else "english"
            assert _language(rig, other) == 1
        else:
            rig.clock.advance(1.6 if operation == "close" else 0.3)
        if collecting and rig.clock.now() >= last_block + 1.5:
            # the pause ended the utterance during that step, with the engine of that moment
            expected.append(rig.node.language)
            collecting = False
    if collecting:
        rig.clock.advance(1.6)
        expected.append(rig.node.language)
    rig.clock.advance(0.7 * len(expected) + 1.0)
    assert rig.texts() == expected


def test_switches_from_another_thread_race_running_recognitions_without_losing_or_doubling() -> None:
    """The ROS case: service handler threads switch while the worker thread recognizes."""

    class Slow(GatedRecognizer):
        def __init__(self, answer: str) -> None:
            super().__init__()
            self.answer = Transcript(answer)
            self.gate.set()

    spies = {"english": Slow("english"), "kinyarwanda": Slow("kinyarwanda")}
    executor = ThreadExecutor()
    rig = Rig(AT_16K, spies["english"], executor=executor, build_engine=spies.__getitem__)
    stop = threading.Event()
    answers: List[int] = []

    def switch() -> None:
        while not stop.is_set():
            for language in ("Kinyarwanda", "English"):
                answers.append(_language(rig, language))

    switcher = threading.Thread(target=switch)
    switcher.start()
    utterances = 200
    for number in range(utterances):
        rig.speak(np.full(100 + number, 0.1, dtype=np.float32), block=100 + number)
        rig.clock.advance(1.6)
    stop.set()
    switcher.join()
    assert executor.shutdown(timeout=30)
    heard = {language: [u.size for u in spy.utterances] for language, spy in spies.items()}
    assert sorted(heard["english"] + heard["kinyarwanda"]) == [100 + n for n in range(utterances)]
    assert set(heard["english"]).isdisjoint(heard["kinyarwanda"])
    assert len(rig.texts()) == utterances
    assert set(answers) == {1} and len(answers) > 2
