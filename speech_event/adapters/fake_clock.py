"""A clock that moves only when told to: timers fire in time order, ties in the order they were set.

Timers may be set from any thread (a recognition worker sets its watchdog); they fire on the
thread that moves the clock.
"""

import heapq
import threading
from typing import Callable, List, Optional, Tuple


class FakeTimer:
    """A timer of the FakeClock: fires its callback when the clock passes its time, unless cancelled."""

    def __init__(self, callback: Callable[[], None]) -> None:
        self.callback = callback
        self.cancelled = False

    def cancel(self) -> None:
        self.cancelled = True


class FakeClock:
    """The Clock port for tests and scenario replay: time moves only by ``advance`` and ``advance_to``."""

    def __init__(self, start: float = 0.0) -> None:
        self._now = start
        self._sequence = 0
        self._queue: List[Tuple[float, int, FakeTimer]] = []
        self._lock = threading.Lock()  # held for the queue, never while a callback runs

    def now(self) -> float:
        return self._now

    def call_at(self, when: float, callback: Callable[[], None]) -> FakeTimer:
        timer = FakeTimer(callback)
        with self._lock:
            heapq.heappush(self._queue, (max(when, self._now), self._sequence, timer))
            self._sequence += 1
        return timer

    def next_due(self) -> Optional[float]:
        """When the next timer that is still set fires; None when none is."""
        with self._lock:
            due = [when for when, _, timer in self._queue if not timer.cancelled]
        return min(due, default=None)

    def advance_to(self, when: float) -> None:
        """Move to ``when``, firing every timer due by then, also those set while firing."""
        if when < self._now:
            raise ValueError(f"the clock cannot go back from {self._now} to {when}")
        while True:
            with self._lock:
                if not self._queue or self._queue[0][0] > when:
                    break
                due, _, timer = heapq.heappop(self._queue)
                self._now = due
            if not timer.cancelled:
                timer.callback()
        self._now = when

    def advance(self, seconds: float) -> None:
        self.advance_to(self._now + seconds)
