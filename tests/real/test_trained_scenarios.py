"""The scenarios on trained weights (Whisper tiny.en: free speech, speculation, partial results,
set_grammar) pass in memory, and publish the same with speculation and partial results off
(fixtures/every_scenario.py says exactly what is compared)."""

from pathlib import Path

import pytest

from fixtures.every_scenario import (
    RECOGNITION_SECONDS,
    check_scenario_ending_at_end_of_speech,
    check_scenario_with_and_without_speculation_and_partials,
)
from fixtures.scenario_files import TRAINED_SCENARIOS


def test_there_are_scenarios_on_trained_weights_for_free_speech_set_grammar_and_people() -> None:
    assert [path.stem for path in TRAINED_SCENARIOS] == [
        "trained_free_speech",
        "trained_people_words",
        "trained_woman_reading",
        "trained_yes_no",
    ]


@pytest.mark.parametrize("recognition_seconds", RECOGNITION_SECONDS)
@pytest.mark.parametrize("path", TRAINED_SCENARIOS, ids=lambda path: path.stem)
def test_every_trained_scenario_passes_and_publishes_the_same_without_speculation_and_without_partials(
    path: Path, recognition_seconds: float
) -> None:
    check_scenario_with_and_without_speculation_and_partials(path, recognition_seconds)


@pytest.mark.parametrize("path", TRAINED_SCENARIOS, ids=lambda path: path.stem)
def test_every_trained_scenario_passes_with_the_turn_ending_at_the_end_of_speech(path: Path) -> None:
    check_scenario_ending_at_end_of_speech(path, 0.0)
