"""When a ROS replay stops its clock, and what it waits for there: what our node did when the same
scenario played in memory (harness/memory_runner.py), which is never what is compared.

The node's own rules say when it acts by itself (a health check, the end of an utterance after a
pause, an early pause or a length cut, a goal's deadline or feedback, a speculation gap): in
memory its timers fire at those times, and the replay stops its clock at each, so a rule's timer
fires on ROS at the time it fires in memory, before the events that come after it.
"""

import math
from dataclasses import dataclass
from typing import List, Tuple

from harness.memory_runner import run_in_memory
from harness.outcome import Outcome, Published
from harness.scenario import Scenario

# After each clock step, the node's timers run; after the step that ends an utterance, its
# recognition runs and its text is published: the runner waits this long for that text.
TIMER_SETTLE = 0.03
TEXT_WAIT = 1.0
# Real time: how long the harness needs, after the node is ready, before the scenario's t = 0.
ALIGN_MARGIN = 0.5
# Real time: the node's checks come this much before the scenario's multiples of the period. In
# sim time (and in memory) a check due at T runs before the events at T; so here too.
CHECK_LEAD = 0.05


@dataclass(frozen=True)
class Schedule:
    """A scenario's run in memory, as a ROS replay of it needs it."""

    rehearsal: Outcome

    @classmethod
    def of(cls, scenario: Scenario) -> "Schedule":
        return cls(run_in_memory(scenario))

    @property
    def stops(self) -> List[float]:
        """Where the clock stops besides the events and the end: each time a timer of the node
        fired in memory (every text and action result came at one of these or at an event)."""
        return self.rehearsal.node_timers

    def due(self, now: float, played: int) -> Tuple[int, int, int]:
        """How many texts, action results and partial texts the node had published by ``now`` in
        memory, with ``played`` events played."""

        def count(items: List[Published]) -> int:
            return sum(1 for item in items if item.time <= now and item.played <= played)

        rehearsal = self.rehearsal
        return count(rehearsal.published), count(rehearsal.results), count(rehearsal.partials)


def scenario_start(node_started: float, now: float, period: float) -> float:
    """Real time: when (on the wall clock of ``now``) the scenario's t = 0 is, so that the node's
    health checks, every ``period`` from ``node_started``, fall at multiples of the period on the
    scenario clock (CHECK_LEAD before them), at least ALIGN_MARGIN from ``now``."""
    checks_passed = math.ceil((now + ALIGN_MARGIN - node_started) / period)
    return node_started + checks_passed * period + CHECK_LEAD
