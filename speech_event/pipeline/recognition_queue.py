"""Step 3 of the pipeline: closed utterances waiting for recognition, bounded by seconds of
audio (``max_backlog``).

When recognition cannot keep up (an engine slower than speech, a hung recognition), an unbounded
queue grows by about 700 MB per hour of 48 kHz speech. Past half the bound the node warns, once
per crossing; past the bound the oldest waiting utterance is dropped and said so, with its
length: the newest speech is what the robot's conversation is about.
"""

import logging
import threading
from collections import deque
from dataclasses import dataclass
from typing import Deque, List, Optional

import numpy as np

from speech_event.grammar import Grammar
from speech_event.pipeline.screen import Discard
from speech_event.ports import Recognizer

_LOG = logging.getLogger("speech_event")


@dataclass(frozen=True)
class RecognitionOutcome:
    """What recognition made of an utterance's audio: the engine's answer as it gave it (checked
    when the utterance is published, under its number), or why there is none."""

    answer: object = None
    discard: Optional[Discard] = None  # not speech: not transcribed at all
    took: float = 0.0  # seconds the engine ran
    error: Optional[BaseException] = None  # the engine failed (or was cancelled)


@dataclass(frozen=True)
class RecognitionJob:
    """A closed utterance waiting for recognition, with the engine and language it goes to."""

    number: int
    started_at: float  # when its first block arrived
    closed_at: float
    last_block_at: float  # when its last block arrived
    audio: np.ndarray
    recognizer: Recognizer  # the engine in use when the utterance closed
    language: str  # the language of that engine
    seconds: float
    grammar: Optional[Grammar] = None  # the grammar in force when it closed (None: free speech)


class RecognitionQueue:
    """The utterances waiting for recognition, oldest first, at most ``max_seconds`` of audio."""

    def __init__(self, max_seconds: float) -> None:
        self._max_seconds = max_seconds
        self._lock = threading.Lock()
        self._jobs: Deque[RecognitionJob] = deque()
        self._seconds = 0.0
        self._warned = False
        self.dropped = 0

    @property
    def seconds(self) -> float:
        """Seconds of audio waiting (not counting a recognition that is running)."""
        with self._lock:
            return self._seconds

    @property
    def waiting(self) -> int:
        """Utterances waiting (not counting a recognition that is running)."""
        with self._lock:
            return len(self._jobs)

    def put(self, job: RecognitionJob) -> List[RecognitionJob]:
        """Queue ``job``; return the oldest jobs dropped to keep within the bound."""
        dropped: List[RecognitionJob] = []
        with self._lock:
            self._jobs.append(job)
            self._seconds += job.seconds
            while self._seconds > self._max_seconds and len(self._jobs) > 1:
                oldest = self._jobs.popleft()
                self._seconds -= oldest.seconds
                dropped.append(oldest)
            self.dropped += len(dropped)
            seconds, warn = self._seconds, self._seconds > self._max_seconds / 2 and not self._warned
            self._warned = self._seconds > self._max_seconds / 2
        if warn:
            _LOG.warning(
                "recognition is falling behind: %.1f s of speech waits (max_backlog %.0f s; past it the "
                "oldest utterance is dropped)",
                seconds,
                self._max_seconds,
            )
        for job in dropped:
            _LOG.error(
                "dropped utterance %d (%.2f s) unrecognized: %.1f s of speech waited, "
                "more than max_backlog %.0f s",
                job.number,
                job.seconds,
                seconds + job.seconds,
                self._max_seconds,
            )
        return dropped

    def take(self) -> Optional[RecognitionJob]:
        """The oldest waiting job, or None when there is none."""
        with self._lock:
            if not self._jobs:
                return None
            job = self._jobs.popleft()
            self._seconds = max(0.0, self._seconds - job.seconds)
            self._warned = self._warned and self._seconds > self._max_seconds / 2
            return job
