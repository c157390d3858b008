"""Every hermetic scenario file passes in memory, publishes the same with speculation and partial
results off, and with the turn ending at the end of speech (fixtures/every_scenario.py says exactly
what is compared)."""

from pathlib import Path

import pytest

from fixtures.every_scenario import (
    RECOGNITION_SECONDS,
    check_scenario_with_every_turn_rule,
)
from fixtures.scenario_files import SCENARIOS


@pytest.mark.parametrize("recognition_seconds", RECOGNITION_SECONDS)
@pytest.mark.parametrize("path", SCENARIOS, ids=lambda path: path.stem)
def test_every_scenario_passes_and_publishes_the_same_under_every_turn_rule(
    path: Path, recognition_seconds: float
) -> None:
    check_scenario_with_every_turn_rule(path, recognition_seconds)
