"""recognition_timeout: a recognition still running past it is said, and stopped where the engine can be."""

import functools
import logging
import threading
from typing import Callable, Optional

from speech_event.pipeline.recognition_queue import RecognitionJob
from speech_event.ports import Clock, Stoppable, Timer

_LOG = logging.getLogger("speech_event")


class Watchdog:
    """Watches one recognition at a time on the node's clock; counts those that overran."""

    def __init__(
        self, clock: Clock, lock: threading.Lock, timeout: float, running: Callable[[RecognitionJob], bool]
    ) -> None:
        """``running(job)``: whether ``job``'s recognition still runs (asked under ``lock``)."""
        self._clock = clock
        self._lock = lock
        self._timeout = timeout
        self._running = running
        self.timed_out = 0

    def watch(self, job: RecognitionJob) -> Optional[Timer]:
        """The recognition of ``job`` starts now; None when recognition_timeout is off."""
        if self._timeout <= 0:
            return None
        return self._clock.call_at(self._clock.now() + self._timeout, functools.partial(self._overdue, job))

    def _overdue(self, job: RecognitionJob) -> None:
        with self._lock:  # under the lock, so a stop never reaches the next utterance's run
            if not self._running(job):
                return
            self.timed_out += 1
            stoppable = isinstance(job.recognizer, Stoppable)
            _LOG.error(
                "recognition of utterance %d (%.2f s) still runs after recognition_timeout %g s: %s",
                job.number,
                job.seconds,
                self._timeout,
                "cancelling it"
                if stoppable
                else "this engine cannot be cancelled; later utterances wait, bounded by max_backlog",
            )
            if isinstance(job.recognizer, Stoppable):
                job.recognizer.stop()
