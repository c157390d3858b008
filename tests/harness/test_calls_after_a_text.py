"""A client's call that waits for the text of the utterance before it (``after = "text"``), as the
Behaviour Controller sets its next grammar only once it has the answer: on the fake clock the text
must be there by the call's time as written, and with slow recognition the call waits for it; on
the wall clock the call waits for it however long recognition takes, and what follows moves later
with the wait (issue 56: causality, not a margin of silence, orders a call after an utterance)."""

import time
from typing import Any, Dict, List

import numpy as np
import pytest

from harness import memory_runner, real_time_runner
from harness.memory_runner import run_in_memory
from harness.real_time_runner import run_in_real_time
from harness.report import passed
from harness.scenario import ScenarioError, SetGrammar, parse_scenario
from harness.schedule import Schedule
from speech_event.config import SpeechEventConfig
from speech_event.ports import Transcript
from speech_event.recognizers.tones import ToneRecognizer

# The robot's question: an answer, then the controller clears the grammar once it has the text;
# 'stop' after it is free speech. 0.5 s of silence is less than the pause (1.5 s): only the wait
# for the text orders the call after the answer.
QUESTION: Dict[str, Any] = {
    "name": "a grammar cleared once the answer's text has come",
    "config": {"end_of_speech": 0.0},  # every turn ends at the pause
    "steps": [
        {"grammar": "yes|no"},
        {"say": "yes"},
        {"silence": 2.0},
        {"grammar": "", "after": "text"},
        {"say": "stop"},
    ],
    "expect": {"published": ["yes", "stop"], "responses": [1, 1]},
}
SLOW = 3.0  # seconds a recognition takes: more than the silence before the call


def _scenario(document: Dict[str, Any] = QUESTION) -> Any:
    return parse_scenario(document, "question.toml", SpeechEventConfig())


def test_the_step_says_it_waits_for_the_text_and_only_text_is_allowed() -> None:
    assert _scenario().steps[3] == SetGrammar("", after_text=True)
    steps = [{"grammar": "", "after": "answer"}]
    with pytest.raises(ScenarioError) as error:
        parse_scenario({**QUESTION, "steps": steps}, "s.toml", SpeechEventConfig())
    assert str(error.value) == "s.toml: steps[0]: 'after' = 'answer' is not allowed; allowed: text"


def test_on_the_fake_clock_the_call_is_made_at_its_time_when_the_text_has_come() -> None:
    outcome = run_in_memory(_scenario())
    assert [item.text for item in outcome.published] == ["yes", "stop"] and outcome.responses == [1, 1]
    assert passed(_scenario(), outcome)


def test_a_call_that_waits_for_a_text_that_has_not_come_by_its_time_is_refused_saying_why() -> None:
    steps: List[Dict[str, Any]] = [{"say": "yes"}, {"silence": 0.5}, {"enable": "false", "after": "text"}]
    with pytest.raises(ScenarioError) as error:
        run_in_memory(_scenario({**QUESTION, "steps": steps}))
    assert str(error.value).startswith("the call at t=")
    assert "waits for the text of the utterance before it" in str(error.value)


def _note_texts_at_calls(monkeypatch: pytest.MonkeyPatch, runner: type) -> List[List[str]]:
    """What the runner had seen published at each of its calls."""
    texts_at_calls: List[List[str]] = []
    call = runner.call  # type: ignore[attr-defined]

    def noted(self: Any, service: str, request: object) -> None:
        texts_at_calls.append([item.text for item in self.outcome.published])
        call(self, service, request)

    monkeypatch.setattr(runner, "call", noted)
    return texts_at_calls


def test_with_slow_recognition_the_call_waits_for_the_text(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    texts_at_calls = _note_texts_at_calls(monkeypatch, memory_runner._InMemory)
    outcome = run_in_memory(_scenario(), recognition_seconds=SLOW)
    assert texts_at_calls == [[], ["yes"]]
    assert [item.text for item in outcome.published] == ["yes", "stop"]


class _SlowTones(ToneRecognizer):
    def transcribe(self, audio: np.ndarray) -> Transcript:
        time.sleep(SLOW)
        return super().transcribe(audio)


def test_on_the_wall_clock_the_call_waits_for_the_text_however_long_recognition_takes(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    scenario = _scenario()
    rehearsal = Schedule.of(scenario)  # recognition takes no time there
    monkeypatch.setattr(Schedule, "of", lambda scenario: rehearsal)
    monkeypatch.setattr("speech_event.recognizers.ToneRecognizer", _SlowTones)
    texts_at_calls = _note_texts_at_calls(monkeypatch, real_time_runner._RealTime)
    outcome = run_in_real_time(scenario)
    assert texts_at_calls == [[], ["yes"]]
    assert [item.text for item in outcome.published] == ["yes", "stop"] and passed(scenario, outcome)
