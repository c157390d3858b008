"""Closed utterances on the recognition worker: queued (bounded by ``max_backlog``, the oldest
waiting one dropped past it), recognized one at a time, oldest first, each watched by
``recognition_timeout`` while it runs, and concluded. While one waits or runs, the worker does
nothing for the utterance still being collected (speech_event/turns/background_runs.py)."""

import threading
from typing import Callable, Optional

from speech_event.pipeline.recognition_queue import RecognitionJob, RecognitionQueue
from speech_event.pipeline.worker import Worker
from speech_event.ports import Timer


class ClosedUtterances:
    """The closed utterances handed to the worker, and the one it recognizes now."""

    def __init__(
        self, queue: RecognitionQueue, lock: threading.Lock, worker: Worker, after_each: Callable[[], None]
    ) -> None:
        """``queue``: where they wait; ``after_each``: called under ``lock`` when the worker has
        finished one."""
        self._queue = queue
        self._lock = lock
        self._worker = worker
        self._after_each = after_each
        self.running: Optional[RecognitionJob] = None  # the utterance being recognized

    def idle(self) -> bool:
        """Under the lock: none is being recognized or waits for it."""
        return self.running is None and self._queue.waiting == 0

    def put(self, job: RecognitionJob) -> None:
        """Under the lock: ``job`` goes to the worker after those waiting."""
        for dropped in self._queue.put(job):
            self._worker.publication.dropped(dropped)
        self._worker.executor.submit(self._run_next)

    def _run_next(self) -> None:
        """One executor job: the oldest waiting utterance (none when it was dropped), watched."""
        watchdog: Optional[Timer] = None
        with self._lock:
            job = self._queue.take()
            if job is None:
                return
            self.running = job
            watchdog = self._worker.watchdog.watch(job)
        try:
            self._worker.publication.conclude(
                job, self._worker.recognize(job.audio, job.recognizer, job.grammar)
            )
        finally:
            with self._lock:
                self.running = None
                if watchdog is not None:
                    watchdog.cancel()
                self._after_each()
