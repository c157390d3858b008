"""Every scenario file, in memory: it passes (what it expects is published), and with speculation
and partial results on (the defaults) and with each of them off, at two recognition times (0 s, and
1 s: recognition overlaps the speech that follows), neither changes what the robot acts on.

- Speculation: the same texts, errors at the same times, transcripts in the same order, each no
  later (so one may now come before an error it used to follow); the same action results and
  service responses.
- Partial results: the same published texts at the same times, results and responses.

The run with the defaults is shared by the three: at 0 s it is the scenario's own run. The
hermetic scenarios are checked so in tests/test_every_scenario.py, those on trained weights in
tests/real/test_trained_scenarios.py.

And with the turn ending at the end of speech (end_of_speech set to 0.3: in free speech too, and
with pocketsphinx): what the scenario expects at 0 s (but its partial results), and at 1 s the
texts of the node that waits for the pause (end_of_speech 0)
(tests/turns/test_end_of_turn.py, and the trained scenarios in tests/real/test_trained_scenarios.py)."""

import dataclasses
from pathlib import Path
from typing import Any, List, Tuple

from harness.memory_runner import run_in_memory
from harness.outcome import Outcome, Published
from harness.report import passed, report
from harness.scenario import Scenario, load_scenario
from speech_event import SOUND_DETECTION_DOWN
from speech_event.config import SpeechEventConfig

RECOGNITION_SECONDS = (0.0, 1.0)


def _errors(outcome: Outcome) -> List[Tuple[float, str]]:
    return [(p.time, p.text) for p in outcome.published if p.text == SOUND_DETECTION_DOWN]


def _transcripts(outcome: Outcome) -> List[Published]:
    return [p for p in outcome.published if p.text != SOUND_DETECTION_DOWN]


def _without(scenario: Scenario, **settings: Any) -> Scenario:
    return dataclasses.replace(scenario, config=dataclasses.replace(scenario.config, **settings))


def check_scenario_with_and_without_speculation_and_partials(path: Path, recognition_seconds: float) -> None:
    """The checks above, on one scenario file at one recognition time."""
    scenario = load_scenario(str(path), SpeechEventConfig())
    assert scenario.config.speculative_recognition and scenario.config.partial_period == 0.5  # defaults
    default = run_in_memory(scenario, recognition_seconds)
    if recognition_seconds == 0.0:  # the time the scenarios' expectations are written for
        assert passed(scenario, default), report(scenario, default)

    plain = run_in_memory(_without(scenario, speculative_recognition=False), recognition_seconds)
    assert _errors(default) == _errors(plain)
    assert [m.text for m in _transcripts(default)] == [m.text for m in _transcripts(plain)]
    assert all(a.time <= b.time + 1e-9 for a, b in zip(_transcripts(default), _transcripts(plain)))
    assert [r.text for r in default.results] == [r.text for r in plain.results]
    assert default.responses == plain.responses

    no_partials = run_in_memory(_without(scenario, partial_period=0.0), recognition_seconds)
    assert default.published == no_partials.published
    assert default.results == no_partials.results
    assert default.responses == no_partials.responses


def check_scenario_ending_at_end_of_speech(path: Path, recognition_seconds: float) -> None:
    """The last check above, on one scenario file at one recognition time."""
    scenario = load_scenario(str(path), SpeechEventConfig())
    ending = _without(scenario, end_of_speech=0.3)
    if scenario.expected_partials is not None:
        # The speculation on the audio up to the end of speech publishes its text as a partial
        # when it is new, before the partial that comes each partial_period would: the partials,
        # and the transcripts among which they come, are not the scenario's.
        ending = dataclasses.replace(ending, expected_partials=None, expected_transcripts=None)
    outcome = run_in_memory(ending, recognition_seconds)
    if recognition_seconds == 0.0:
        assert passed(ending, outcome), report(ending, outcome)
    else:
        waiting = run_in_memory(_without(scenario, end_of_speech=0.0), recognition_seconds)
        assert [p.text for p in outcome.published] == [p.text for p in waiting.published]
