"""When a replay on a real clock (ROS, or the wall clock in memory) stops its clock, and what it
waits for there: what our node did when the same scenario played in memory
(harness/memory_runner.py), which is never what is compared.

The node's own rules say when it acts by itself (a health check, the end of an utterance after a
pause, an early pause or a length cut, a goal's deadline or feedback, a speculation gap): in
memory its timers fire at those times, and the replay stops its clock at each, so a rule's timer
fires on ROS at the time it fires in memory, before the events that come after it.
"""

import math
import time
from dataclasses import dataclass
from typing import Callable, List, Optional, Sequence, Tuple

from harness.memory_runner import run_in_memory
from harness.outcome import Outcome, Published
from harness.scenario import Scenario
from harness.timeline import Event, Publish
from speech_event.topics import SOUND_DETECTION_DOWN

# After each clock step, the node's timers run; after the step that ends an utterance, its
# recognition runs and its text is published: the runner waits for that text until it comes, or
# for at most TEXT_DEADLINE. A fixed second failed CI on a busy machine (pocketsphinx's language
# model took longer); the bound is the slowest engine the scenarios run (pocketsphinx within a
# grammar, 0.3 s a second of speech on an idle 2-core machine) on the longest utterance (10 s),
# with a core busy elsewhere and the rest of the suite beside it: generous, since a text that comes
# costs only its own time. Once a wait has run out in a scenario, its later waits last
# TEXT_WAIT_AFTER_MISS: one missing text fails the scenario once, not at every later event.
# TIMER_SETTLE is all a node that publishes no /diagnostics (another than ours) gets for its timers
# at a clock step; ours is waited for (harness/ros/runner.py).
TIMER_SETTLE = 0.03
TEXT_DEADLINE = 30.0
TEXT_WAIT_AFTER_MISS = 1.0
# ROS time is whole nanoseconds: a time sent as a float and read back is within this of it.
CLOCK_RESOLUTION = 1e-6
# Real time: how long the harness needs, after the node is ready, before the scenario's t = 0: on
# a roscore, for the node's process; in memory nothing (the node is ready once constructed, and its
# first check comes a period later: waiting for it cost every scenario up to 5 s of wall clock).
ALIGN_MARGIN = 0.5
IN_MEMORY_ALIGN_MARGIN = 0.0
# Real time: the node's checks come this much before the scenario's multiples of the period. In
# sim time (and in memory) a check due at T runs before the events at T; so here too.
CHECK_LEAD = 0.05
# Real time: a client's call answered more than this after its time holds the events after it back
# (ScenarioWallClock.answered). Played late by less, they only come closer together by that much:
# the scenarios' silences between utterances (2 s or more) stay longer than the pause that ends an
# utterance (1.5 s).
LATE_ANSWER = 0.25


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

    def due(self, now: float, played: int) -> "Due":
        """What the node had published by ``now`` in memory, with ``played`` events played."""

        def by_now(items: List[Published]) -> Tuple[str, ...]:
            return tuple(item.text for item in items if item.time <= now and item.played <= played)

        rehearsal = self.rehearsal
        return Due(by_now(rehearsal.published), by_now(rehearsal.results), by_now(rehearsal.partials))


@dataclass(frozen=True)
class Due:
    """The texts, action results and partial texts a replay waits for, in order.

    Each is waited for as itself, not counted: a text the node published that memory did not (a
    health check that ran late and saw an outage that came after it) must not stand in for one
    still to come, or the replay would go on, and end, before it came."""

    texts: Tuple[str, ...]
    results: Tuple[str, ...]
    partials: Tuple[str, ...]

    def missing(self, observed: Outcome) -> str:
        """What of this has not come in ``observed`` ('' when all has), in words."""
        counts = (
            (_unmatched(self.texts, observed.published), "text(s)"),
            (_unmatched(self.results, observed.results), "action result(s)"),
            (_unmatched(self.partials, observed.partials), "partial text(s)"),
        )
        return ", ".join(f"{count} {what}" for count, what in counts if count > 0)

    def wait(self, observed: Outcome, patience: float, now: Callable[[], float]) -> Optional[str]:
        """Wait until ``observed`` holds all of this, for at most ``patience`` seconds; None once it
        does, else what was missing, when (``now``: the scenario clock) and how long it was awaited."""
        began = time.monotonic()
        while self.missing(observed) and time.monotonic() < began + patience:
            time.sleep(0.002)
        missing = self.missing(observed)
        if not missing:
            return None
        return (
            f"at t={now():.3f} s, waited {time.monotonic() - began:.1f} s for {missing} "
            "that the node published by then in memory"
        )


def _unmatched(due: Tuple[str, ...], observed: List[Published]) -> int:
    """How many of ``due`` are not in ``observed`` in their order (others may come between): the
    soundDetection errors in theirs and the other texts in theirs, as a real-time report compares
    them (harness/report.py). On the wall clock a recognition still running when a check finds
    soundDetection down is published after the error: people_digits' 'three' after the outage's
    first error, and the replay waited 30 s at its end for what had come."""
    return sum(
        _unmatched_in_order(
            [text for text in due if (text == SOUND_DETECTION_DOWN) == errors],
            [item.text for item in observed if (item.text == SOUND_DETECTION_DOWN) == errors],
        )
        for errors in (False, True)
    )


def _unmatched_in_order(due: List[str], observed: List[str]) -> int:
    matched = 0
    for text in observed:
        if matched < len(due) and text == due[matched]:
            matched += 1
    return len(due) - matched


@dataclass(frozen=True)
class HealthChecks:
    """When a node that started at ``started_at`` checks soundDetection: every ``period`` after."""

    started_at: float
    period: float

    def at(self, when: float) -> bool:
        """Whether one of the checks falls at ``when``."""
        periods = (when - self.started_at) / self.period
        nearest = round(periods)
        return nearest >= 1 and abs(self.started_at + nearest * self.period - when) <= CLOCK_RESOLUTION


class ScenarioWallClock:
    """The scenario clock of a replay in real time: the wall clock from t = 0 on, moved later by
    whole health-check periods when a client's call was answered late, or a block that ends an
    utterance went out late (played_late).

    The robot's clients wait for the node's answer before they go on (the Behaviour Controller sets
    a grammar, then the robot asks its question), so what follows a call comes after the answer.
    Played at their old times instead, the events after a late answer came at once: after a
    set_grammar answered in 3 s, 'yes', the 2 s of silence after it and 'no' reached the node
    together, one utterance that is no phrase of 'yes|no' (scenarios/trained_yes_no.toml in real
    time beside a busy machine, with the silence's encoding in set_grammar). Moved by whole periods,
    the node's checks still fall at multiples of the period on the scenario clock. A call made in
    the middle of speech and answered late would so part that speech in two: the scenarios call
    before speech or in its pauses, as the robot's clients do when they set a grammar or listen."""

    def __init__(self) -> None:
        self._start = time.monotonic()
        self._period = math.inf

    def start(self, node_started: float, period: float, margin: float = ALIGN_MARGIN) -> None:
        """Make t = 0 the instant scenario_start gives, and wait for it."""
        now = time.time()
        self._begin_in(scenario_start(node_started, now, period, margin) - now, period)

    def start_now(self, period: float, margin: float = ALIGN_MARGIN) -> None:
        """Make t = 0 ``margin`` from now, whenever the node's checks come (a scenario in which
        soundDetection never goes down: they find it up, whenever they run), and wait for it."""
        self._begin_in(margin, period)

    def _begin_in(self, seconds: float, period: float) -> None:
        """Make t = 0 ``seconds`` from now, moved later by whole ``period``s when late, and wait for it."""
        self._period = period
        self._start = time.monotonic() + seconds
        time.sleep(max(0.0, self._start - time.monotonic()))

    def now(self) -> float:
        """Now on the scenario clock."""
        return time.monotonic() - self._start

    def sleep_until(self, when: float) -> None:
        """Wait until ``when`` on the scenario clock (no wait once it has passed)."""
        time.sleep(max(0.0, self._start + when - time.monotonic()))

    def played_late(self, played_at: float, next_at: float, pause: float) -> None:
        """A block due at ``played_at`` has gone out: when more than LATE_ANSWER late and the next
        event is ``pause`` or more after it (the silence after an utterance), the rest of the
        scenario moves later by the whole periods that cover the delay, so that the silence keeps
        its length. Played at their old times instead, the events after it came closer: on a busy
        machine the tones 'a' went out 0.6 s late, and 'go to the kitchen' 2 s after it in the
        scenario joined it, one utterance (min_utterance_length in real time on a roscore)."""
        if next_at - played_at >= pause:
            self._later_if_late(played_at)

    def answered(self, asked_at: float) -> None:
        """A call made at ``asked_at`` (scenario clock) has been answered: when more than
        LATE_ANSWER later, the rest of the scenario moves later by the whole periods that cover it."""
        self._later_if_late(asked_at)

    def _later_if_late(self, due_at: float) -> None:
        """What was due at ``due_at`` happened now: when more than LATE_ANSWER late, the rest of the
        scenario moves later by the whole periods that cover the delay (so the node's checks still
        fall at multiples of the period on the scenario clock)."""
        late = self.now() - due_at
        if late > LATE_ANSWER:
            self._start += math.ceil(late / self._period) * self._period


def scenario_start(node_started: float, now: float, period: float, margin: float = ALIGN_MARGIN) -> float:
    """Real time: when (on the wall clock of ``now``) the scenario's t = 0 is, so that the node's
    health checks, every ``period`` from ``node_started``, fall at multiples of the period on the
    scenario clock (CHECK_LEAD before them), at least ``margin`` from ``now``: CHECK_LEAD after the
    node's start where that is still far enough ahead (its first check then comes at t = period, as
    in memory), else just after the first check that is."""
    periods = max(0, math.ceil((now + margin - CHECK_LEAD - node_started) / period))
    return node_started + periods * period + CHECK_LEAD


def block_just_played(events: Sequence[Event], played: int, now: float) -> Optional[Tuple[float, float]]:
    """When the event just played (the ``played``-th, at ``now``) is a block with another event
    after it: its time and the next event's; else None."""
    if not 0 < played < len(events):
        return None
    last = events[played - 1]
    if not isinstance(last, Publish) or last.time != now:
        return None
    return last.time, events[played].time
