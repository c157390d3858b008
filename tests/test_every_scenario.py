"""Every hermetic scenario file passes in memory, and publishes the same with speculation and partial
results off (fixtures/every_scenario.py says exactly what is compared)."""

from pathlib import Path

import pytest

from fixtures.every_scenario import (
    RECOGNITION_SECONDS,
    check_scenario_with_and_without_speculation_and_partials,
)
from fixtures.scenario_files import SCENARIOS


@pytest.mark.parametrize("recognition_seconds", RECOGNITION_SECONDS)
@pytest.mark.parametrize("path", SCENARIOS, ids=lambda path: path.stem)
def test_every_scenario_passes_and_publishes_the_same_without_speculation_and_without_partials(
    path: Path, recognition_seconds: float
) -> None:
    check_scenario_with_and_without_speculation_and_partials(path, recognition_seconds)
