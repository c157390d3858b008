"""The in-memory replay on the wall clock (harness/real_time_runner.py): what it collects, and a
text that never comes failing the scenario with how long it was waited for. Every scenario played
so beside two busy processes: tests/real/test_scenarios_in_real_time.py."""

import time

import pytest

from fixtures.paths import ROOT
from harness.memory_runner import SoundDetectionOnTheBus
from harness.outcome import REAL_TIME
from harness.real_time_runner import run_in_real_time
from harness.report import passed, report
from harness.scenario import load_scenario, parse_scenario
from harness.schedule import Schedule
from harness.timeline import build_timeline
from speech_event.config import SpeechEventConfig
from speech_event.interfaces.services import RuntimeControl
from speech_event.messages import Float32MultiArray, SetGrammarResponse
from speech_event.pipeline.publication import Publication

# Two commands, two seconds apart, and a recognise_speech goal for the second.
SCENARIO = {
    "name": "two commands",
    "steps": [{"say": "go left"}, {"silence": 2.0}, {"listen": 5.0}, {"say": "stop"}],
    "expect": {"published": ["go left", "stop"], "results": ["stop"]},
}


def test_the_texts_and_results_come_on_the_scenario_clock_after_their_speech() -> None:
    scenario = parse_scenario(SCENARIO, "two.toml", SpeechEventConfig())
    outcome = run_in_real_time(scenario)
    assert outcome.clock == REAL_TIME
    assert [message.text for message in outcome.published] == ["go left", "stop"]
    assert [result.text for result in outcome.results] == ["stop"]
    assert outcome.partials == [] and outcome.gave_up == []
    # each text after its utterance's pause (1.5 s), in their order
    first, second = (message.time for message in outcome.published)
    assert 1.5 < first < second and passed(scenario, outcome)


def test_a_text_that_never_comes_fails_the_scenario_saying_how_long_it_was_waited_for(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    scenario = parse_scenario(
        {"name": "one", "steps": [{"say": "go left"}], "expect": {"published": ["go left"]}},
        "one.toml",
        SpeechEventConfig(),
    )
    rehearsal = Schedule.of(scenario)  # in memory, its text comes
    monkeypatch.setattr(Schedule, "of", lambda scenario: rehearsal)
    monkeypatch.setattr(Publication, "conclude", lambda self, job, outcome: None)  # now it publishes nothing
    outcome = run_in_real_time(scenario, text_deadline=0.5)
    assert outcome.published == [] and not passed(scenario, outcome)
    (gave_up,) = outcome.gave_up
    assert gave_up.startswith("at t=") and gave_up.endswith(
        " s, waited 0.5 s for 1 text(s) that the node published by then in memory"
    ), gave_up
    assert "      gave up: " + gave_up in report(scenario, outcome)


def test_what_follows_a_late_answer_comes_after_it_with_the_scenario_silences_kept(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A set_grammar answered 3 s late: 'yes', 2 s of silence and 'no' after it are two utterances,
    as in memory. Played at their old times they reached the node at once, one utterance 'yes no'
    that is no phrase of the grammar, and neither was published."""
    scenario = parse_scenario(
        {
            "name": "a question after a slow set_grammar",
            "steps": [{"grammar": "yes|no"}, {"say": "yes"}, {"silence": 2.0}, {"say": "no"}],
            "expect": {"published": ["yes", "no"], "responses": [1]},
        },
        "slow.toml",
        SpeechEventConfig(end_of_speech=0.0),  # each turn ends at the pause, which the times below tell
    )
    rehearsal = Schedule.of(scenario)
    monkeypatch.setattr(Schedule, "of", lambda scenario: rehearsal)
    answer = RuntimeControl.on_set_grammar

    def answered_late(control: RuntimeControl, request: object) -> SetGrammarResponse:
        response = answer(control, request)
        time.sleep(3.0)
        return response

    monkeypatch.setattr(RuntimeControl, "on_set_grammar", answered_late)
    outcome = run_in_real_time(scenario)
    assert [message.text for message in outcome.published] == ["yes", "no"]
    assert outcome.responses == [1] and outcome.gave_up == [] and passed(scenario, outcome)
    # the scenario clock moved with the answer (by a health-check period): each text a pause after its speech
    first, second = (message.time for message in outcome.published)
    assert 1.5 < first < 2.0 + 1.5 < second


def test_a_block_that_goes_out_late_before_a_silence_does_not_join_the_speech_after_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """min_utterance_length on a busy roscore: 'a' went out 0.6 s late, 'go to the kitchen' came
    2 s after it on the scenario clock, 1.4 s after it on the node's, and the two were one
    utterance. The events after a late block before a silence move later with it."""
    scenario = load_scenario(ROOT / "scenarios" / "min_utterance_length.toml", SpeechEventConfig())
    last_of_a = sum(1 for event in build_timeline(scenario).events if event.time < 1.0) - 1
    publish = SoundDetectionOnTheBus.publish

    def late(sound_detection: SoundDetectionOnTheBus, index: int, message: Float32MultiArray) -> None:
        if index == last_of_a:
            time.sleep(0.8)
        publish(sound_detection, index, message)

    monkeypatch.setattr(SoundDetectionOnTheBus, "publish", late)
    outcome = run_in_real_time(scenario)
    assert [message.text for message in outcome.published] == ["go to the kitchen"]
    assert passed(scenario, outcome)
