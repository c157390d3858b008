"""The wall clock, for the node on the in-memory bus in real time (the driver without ROS)."""

import threading
import time
from typing import Callable


class SystemTimer:
    """A timer of the SystemClock: a daemon threading.Timer, ``delay`` seconds from now."""

    def __init__(self, delay: float, callback: Callable[[], None]) -> None:
        self._timer = threading.Timer(max(0.0, delay), callback)
        self._timer.daemon = True  # a pending timer never keeps the process alive
        self._timer.start()

    def cancel(self) -> None:
        self._timer.cancel()


class SystemClock:
    """Seconds since the epoch (time.time); each timer is a thread of its own."""

    def now(self) -> float:
        return time.time()

    def call_at(self, when: float, callback: Callable[[], None]) -> SystemTimer:
        return SystemTimer(when - time.time(), callback)
