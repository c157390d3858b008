"""Periodic: a callback at start + P, start + 2P, ... that late timers and failing callbacks do not shift."""

import logging
from typing import Callable, Dict, List, Tuple

import pytest

from speech_event.adapters.fake_clock import FakeClock, FakeTimer
from speech_event.interfaces.periodic import Periodic


class _LateClock:
    """A clock whose timers fire only when the test says, as late as it likes."""

    def __init__(self, now: float) -> None:
        self.time = now
        self.requested: List[float] = []
        self._timers: List[FakeTimer] = []

    def now(self) -> float:
        return self.time

    def call_at(self, when: float, callback: Callable[[], None]) -> FakeTimer:
        self.requested.append(when)
        self._timers.append(FakeTimer(callback))
        return self._timers[-1]

    def fire_latest_at(self, now: float) -> None:
        self.time = now
        self._timers[-1].callback()


@pytest.mark.parametrize(
    ("start", "expected"),
    [
        pytest.param({"start": 9.5}, [11.5, 13.5, 15.5], id="from_the_start_it_is_given"),
        pytest.param({}, [12.0, 14.0, 16.0], id="without_a_start_from_now"),
    ],
)
def test_it_runs_at_multiples_of_the_period(start: Dict[str, float], expected: List[float]) -> None:
    clock = FakeClock(10.0)
    times: List[float] = []
    Periodic(clock, 2.0, lambda: times.append(clock.now()), **start)
    clock.advance_to(16.0)
    assert times == expected


def test_a_late_timer_does_not_delay_the_runs_after_it() -> None:
    clock = _LateClock(1.0)
    runs: List[float] = []
    Periodic(clock, 0.5, lambda: runs.append(clock.now()))
    clock.fire_latest_at(1.8)  # due at 1.5
    clock.fire_latest_at(2.3)  # due at 2.0
    clock.fire_latest_at(2.5)
    assert clock.requested == [1.5, 2.0, 2.5, 3.0]
    assert runs == [1.8, 2.3, 2.5]


def test_after_cancel_it_never_runs_again_and_a_second_cancel_is_harmless() -> None:
    clock = FakeClock()
    times: List[float] = []
    periodic = Periodic(clock, 1.0, lambda: times.append(clock.now()))
    clock.advance_to(2.5)
    periodic.cancel()
    periodic.cancel()
    clock.advance_to(10.0)
    assert times == [1.0, 2.0]


def test_a_task_that_cancels_its_own_periodic_is_not_run_again() -> None:
    clock = FakeClock()
    times: List[float] = []

    def once() -> None:
        times.append(clock.now())
        periodic.cancel()

    periodic = Periodic(clock, 1.0, once)
    clock.advance_to(5.0)
    assert times == [1.0]


def test_a_failing_task_is_logged_with_its_traceback_and_runs_again(caplog: pytest.LogCaptureFixture) -> None:
    clock = FakeClock()
    runs: List[float] = []

    def fails_first() -> None:
        runs.append(clock.now())
        if len(runs) == 1:
            raise RuntimeError("the check broke")

    Periodic(clock, 0.5, fails_first)
    with caplog.at_level(logging.ERROR, logger="speech_event"):
        clock.advance_to(1.5)
    assert runs == [0.5, 1.0, 1.5]
    logged: List[Tuple[str, str]] = [
        (record.getMessage(), repr(record.exc_info[1]) if record.exc_info else "")
        for record in caplog.records
    ]
    assert logged == [("a periodic task failed; it runs again in 0.5 s", "RuntimeError('the check broke')")]
