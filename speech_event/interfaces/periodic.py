"""A callback run at start + P, start + 2P, ... on any Clock, without drift."""

import logging
from typing import Callable, Optional

from speech_event.ports import Clock, Timer

_LOG = logging.getLogger("speech_event")


class Periodic:
    """Calls ``callback`` every ``period`` seconds from ``start`` (default: now) until cancelled."""

    def __init__(
        self, clock: Clock, period: float, callback: Callable[[], None], start: Optional[float] = None
    ) -> None:
        self._clock = clock
        self._period = period
        self._callback = callback
        self._start = clock.now() if start is None else start
        self._count = 0
        self._timer: Optional[Timer] = None
        self._schedule_next()

    def cancel(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def _schedule_next(self) -> None:
        # Each time is computed from the start, so timer latency never accumulates.
        self._timer = self._clock.call_at(self._start + (self._count + 1) * self._period, self._fire)

    def _fire(self) -> None:
        self._count += 1
        self._schedule_next()
        try:
            self._callback()
        except Exception:  # a failing check must not stop the checks after it
            _LOG.exception("a periodic task failed; it runs again in %.1f s", self._period)
