"""The scenario clock of the replays in real time (harness/schedule.py): t = 0 just after a health
check, and a call answered late moving the rest of the scenario by whole periods."""

from typing import List

import pytest

from harness import schedule
from harness.schedule import (
    ALIGN_MARGIN,
    CHECK_LEAD,
    LATE_ANSWER,
    ScenarioWallClock,
    block_just_played,
    scenario_start,
)
from harness.timeline import CallService, Event, Publish


class _Time:
    """time.time, time.monotonic (an hour apart) and time.sleep, moved by hand."""

    def __init__(self) -> None:
        self.now = 1000.0
        self.slept: List[float] = []

    def time(self) -> float:
        return self.now + 3600.0

    def monotonic(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        self.slept.append(seconds)
        self.now += seconds


@pytest.fixture
def clock_time(monkeypatch: pytest.MonkeyPatch) -> _Time:
    fake = _Time()
    monkeypatch.setattr(schedule, "time", fake)
    return fake


def test_t_0_comes_just_after_a_health_check_at_least_the_margin_from_now() -> None:
    assert scenario_start(node_started=100.0, now=101.0, period=5.0) == 105.0 + CHECK_LEAD
    assert scenario_start(node_started=100.0, now=104.8, period=5.0) == 110.0 + CHECK_LEAD


def test_with_no_margin_t_0_comes_just_after_the_nodes_start_while_that_is_ahead() -> None:
    # in memory: the node is ready once constructed, and t = 0 need not wait for its first check
    assert scenario_start(node_started=100.0, now=100.01, period=5.0, margin=0.0) == 100.0 + CHECK_LEAD
    assert scenario_start(node_started=100.0, now=100.0 + CHECK_LEAD + 0.01, period=5.0, margin=0.0) == (
        105.0 + CHECK_LEAD
    )
    assert scenario_start(node_started=100.0, now=100.01, period=5.0) == 105.0 + CHECK_LEAD  # ROS's margin


def test_where_checks_cannot_matter_the_clock_starts_the_margin_from_now(clock_time: _Time) -> None:
    # soundDetection never goes down: the node's next check, up to a period away, is not waited for
    clock = ScenarioWallClock()
    clock.start_now(period=5.0)
    assert clock.now() == 0.0 and clock_time.slept == [pytest.approx(ALIGN_MARGIN)]


def test_the_clock_starts_after_a_check_and_sleeps_to_each_time(clock_time: _Time) -> None:
    clock = ScenarioWallClock()
    clock.start(node_started=clock_time.time() - 1.0, period=5.0)
    assert clock.now() == 0.0 and clock_time.slept == [pytest.approx(4.0 + CHECK_LEAD)]
    clock.sleep_until(2.5)
    assert clock.now() == pytest.approx(2.5)
    clock_time.now += 1.0  # played late: nothing to wait for
    clock.sleep_until(3.0)
    assert clock.now() == pytest.approx(3.5) and clock_time.slept[-1] == 0.0


def test_a_late_answer_moves_the_rest_by_the_whole_periods_that_cover_it(clock_time: _Time) -> None:
    clock = ScenarioWallClock()
    clock.start(node_started=clock_time.time(), period=5.0)
    clock_time.now += LATE_ANSWER  # answered in time: nothing moves
    clock.answered(0.0)
    assert clock.now() == pytest.approx(LATE_ANSWER)
    clock_time.now += 6.0  # a call at t = 0.25 answered at 6.25: two periods
    clock.answered(LATE_ANSWER)
    assert clock.now() == pytest.approx(6.0 + LATE_ANSWER - 10.0)
    clock.sleep_until(
        LATE_ANSWER
    )  # the next event, at the call's time: 10 s after the call on the wall clock
    assert clock_time.slept[-1] == pytest.approx(10.0 - 6.0)


def test_a_block_late_before_a_silence_moves_the_rest_so_the_silence_keeps_its_length(
    clock_time: _Time,
) -> None:
    clock = ScenarioWallClock()
    clock.start(node_started=clock_time.time(), period=5.0)
    clock.sleep_until(1.0)
    clock_time.now += 0.6  # the block due at 1.0 went out at 1.6
    clock.played_late(1.0, 1.085, pause=1.5)  # the next block of the same utterance: nothing moves
    assert clock.now() == pytest.approx(1.6)
    clock.played_late(1.0, 3.0, pause=1.5)  # the silence after it: one period later
    assert clock.now() == pytest.approx(1.6 - 5.0)
    clock_time.now += LATE_ANSWER - 0.6 + 5.0  # late by no more than LATE_ANSWER: nothing moves
    clock.played_late(clock.now() - LATE_ANSWER, 9.0, pause=1.5)
    assert clock.now() == pytest.approx(1.0 + LATE_ANSWER)


def test_only_a_block_just_played_with_an_event_after_it_is_one() -> None:
    events: List[Event] = [Publish(0.5, None), Publish(0.6, None), CallService(3.0, "s", None)]
    assert block_just_played(events, 2, 0.6) == (0.6, 3.0)
    assert block_just_played(events, 1, 0.5) == (0.5, 0.6)
    assert block_just_played(events, 2, 3.0) is None  # played at an earlier time
    assert block_just_played(events, 3, 3.0) is None  # a call, and the last event
    assert block_just_played(events, 0, 0.0) is None
