"""Executors that run recognition off the subscriber callback, one job at a time, in order."""

import logging
import queue
import threading
from typing import Callable, Optional

from speech_event.ports import Clock

_LOG = logging.getLogger("speech_event")


class ClockExecutor:
    """A single worker simulated on a clock: deterministic, for the fake clock.

    A job starts when the worker is free and finishes ``job_seconds`` of clock time later, which
    is when it runs. With 0 it runs right after the callback that submitted it, at the same time.
    """

    def __init__(self, clock: Clock, job_seconds: float = 0.0) -> None:
        self._clock = clock
        self._job_seconds = job_seconds
        self._free_at = clock.now()

    @property
    def free_at(self) -> float:
        """When the worker will have finished every job submitted so far."""
        return self._free_at

    def submit(self, job: Callable[[], None]) -> None:
        finish = max(self._free_at, self._clock.now()) + self._job_seconds
        self._free_at = finish
        self._clock.call_at(finish, job)


class ThreadExecutor:
    """One worker thread and an unbounded queue: a slow recognition never blocks the callback."""

    def __init__(self, name: str = "speech_event_recognition") -> None:
        # Annotations inside a function are never evaluated, so the 3.9 generic is safe on 3.8.
        self._jobs: queue.Queue[Optional[Callable[[], None]]] = queue.Queue()  # novermin
        self._thread = threading.Thread(target=self._work, name=name, daemon=True)
        self._thread.start()

    def submit(self, job: Callable[[], None]) -> None:
        self._jobs.put(job)

    def shutdown(self, timeout: float) -> bool:
        """Let the queued jobs finish for up to ``timeout`` s; True if the worker stopped."""
        self._jobs.put(None)
        self._thread.join(timeout)
        return not self._thread.is_alive()

    def _work(self) -> None:
        while True:
            job = self._jobs.get()
            if job is None:
                return
            try:
                job()
            except BaseException:  # the worker must outlive any failing job, SystemExit included
                _LOG.exception("a recognition job failed; the recognition worker goes on")
