"""Executors that run recognition off the subscriber callback, one job at a time, in order."""

import logging
import queue
import threading
from dataclasses import dataclass
from typing import Callable, Optional

from speech_event.ports import Clock

_LOG = logging.getLogger("speech_event")


class _ClockJob:
    """A job of the simulated worker: it occupies the worker from ``start`` to ``finish``, and
    runs at ``finish``. Cancelled before then, it never runs, and a worker it was the last job of
    is free again at once."""

    def __init__(
        self, executor: "ClockExecutor", job: Callable[[], None], start: float, finish: float
    ) -> None:
        self._executor = executor
        self._job = job
        self.start, self.finish = start, finish
        self.done = False
        self.timer = executor.clock.call_at(finish, self._run)

    def _run(self) -> None:
        self.done = True
        self._job()

    def cancel(self) -> None:
        if self.done:
            return
        self.done = True
        self.timer.cancel()
        if self._executor.free_at == self.finish:
            self._executor.release(max(self.start, self._executor.clock.now()))


class ClockExecutor:
    """A single worker simulated on a clock: deterministic, for the fake clock.

    A job starts when the worker is free and finishes ``job_seconds`` of clock time later (the
    simulated recognition time), which is when it runs. With 0 it runs right after the callback
    that submitted it, at the same time.
    """

    def __init__(self, clock: Clock, job_seconds: float = 0.0) -> None:
        self.clock = clock
        self._job_seconds = job_seconds
        self._free_at = clock.now()

    @property
    def free_at(self) -> float:
        """When the worker will have finished every job submitted so far."""
        return self._free_at

    def release(self, when: float) -> None:
        """The last job was cancelled: the worker is free from ``when``."""
        self._free_at = when

    def submit(self, job: Callable[[], None]) -> _ClockJob:
        """Run ``job`` once the worker is free and ``job_seconds`` have passed."""
        start = max(self._free_at, self.clock.now())
        finish = start + self._job_seconds
        self._free_at = finish
        return _ClockJob(self, job, start, finish)


@dataclass
class _ThreadJob:
    job: Callable[[], None]
    cancelled: bool = False

    def cancel(self) -> None:
        self.cancelled = True


class ThreadExecutor:
    """One worker thread and an unbounded queue: a slow recognition never blocks the callback."""

    def __init__(self, name: str = "speech_event_recognition") -> None:
        # Annotations inside a function are never evaluated, so the 3.9 generic is safe on 3.8.
        self._jobs: queue.Queue[Optional[_ThreadJob]] = queue.Queue()  # novermin
        self._thread = threading.Thread(target=self._work, name=name, daemon=True)
        self._thread.start()

    def submit(self, job: Callable[[], None]) -> _ThreadJob:
        """Queue ``job`` for the worker thread."""
        handle = _ThreadJob(job)
        self._jobs.put(handle)
        return handle

    def shutdown(self, timeout: float) -> bool:
        """Let the queued jobs finish for up to ``timeout`` s; True if the worker stopped."""
        self._jobs.put(None)
        self._thread.join(timeout)
        return not self._thread.is_alive()

    def _work(self) -> None:
        while True:
            handle = self._jobs.get()
            if handle is None:
                return
            if handle.cancelled:
                continue
            try:
                handle.job()
            except BaseException:  # the worker must outlive any failing job, SystemExit included
                _LOG.exception("a recognition job failed; the recognition worker goes on")
