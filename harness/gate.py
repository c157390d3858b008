"""The driver's speech gate, as the robot's soundDetection gates its microphone (seed, Table 2).

The stream is cut into ``chunk_size``-sample chunks counted from its first sample, whatever blocks
the audio arrives in; a chunk is speech when any sample reaches ``speech_amplitude_threshold``. Each
speech chunk is published with ``utterance_time_buffer`` samples before it (pre-roll) and after it
(hang-over), clipped at the ends of the stream; regions closer than that merge, and no sample is
published twice. Everything else is silence and is not published at all.

Streaming: ``feed`` takes blocks of any size as they come (a microphone callback, a file read) and
returns what can be published now, each piece with the index of its first sample in the stream.
"""

from collections import deque
from dataclasses import dataclass
from typing import Callable, Deque, List, Optional, Tuple

import numpy as np

Piece = Tuple[int, np.ndarray]  # (index of its first sample in the stream, samples)
# Optional second opinion on a chunk the amplitude calls speech (Silero VAD in noisy rooms).
ChunkCheck = Callable[[np.ndarray], bool]


@dataclass(frozen=True)
class GateSettings:
    chunk_size: int
    threshold: float
    buffer: int  # samples published before and after speech


class SpeechGate:
    def __init__(self, settings: GateSettings, is_speech: Optional[ChunkCheck] = None) -> None:
        self._settings = settings
        self._is_speech = is_speech
        self._partial = np.zeros(0, dtype=np.float32)  # the chunk being filled
        self._position = 0  # stream index of the first sample of the chunk being filled
        self._held: Deque[Piece] = deque()  # unpublished samples just before it, at most ``buffer``
        self._held_samples = 0
        self._hang = 0  # samples still to publish after the last speech chunk

    def feed(self, samples: np.ndarray) -> List[Piece]:
        samples = np.asarray(samples, dtype=np.float32).reshape(-1)
        size = self._settings.chunk_size
        published: List[Piece] = []
        while samples.size:
            room = size - self._partial.size
            self._partial = np.concatenate([self._partial, samples[:room]])
            samples = samples[room:]
            if self._partial.size == size:
                published += self._chunk(self._partial)
                self._partial = np.zeros(0, dtype=np.float32)
        return published

    def finish(self) -> List[Piece]:
        """The end of the stream: its last, short chunk is judged like the others."""
        last, self._partial = self._partial, np.zeros(0, dtype=np.float32)
        return self._chunk(last) if last.size else []

    def _chunk(self, chunk: np.ndarray) -> List[Piece]:
        start = self._position
        self._position += chunk.size
        loud = chunk.size > 0 and float(np.max(np.abs(chunk))) >= self._settings.threshold
        if loud and self._is_speech is not None:
            loud = self._is_speech(chunk)
        if loud:
            published = [*self._held, (start, chunk)]
            self._held.clear()
            self._held_samples = 0
            self._hang = self._settings.buffer
            return published
        published = []
        if self._hang:
            tail = chunk[: self._hang]
            published.append((start, tail))
            self._hang -= tail.size
            chunk, start = chunk[tail.size :], start + tail.size
        if chunk.size:
            self._hold(start, chunk)
        return published

    def _hold(self, start: int, samples: np.ndarray) -> None:
        """Keep the last ``buffer`` unpublished samples, for the pre-roll of speech to come."""
        keep = self._settings.buffer
        if keep == 0:
            return
        if samples.size >= keep:
            self._held.clear()
            self._held.append((start + samples.size - keep, samples[-keep:]))
            self._held_samples = keep
            return
        self._held.append((start, samples))
        self._held_samples += samples.size
        while self._held_samples > keep:
            first_start, first = self._held.popleft()
            excess = self._held_samples - keep
            if first.size > excess:
                self._held.appendleft((first_start + excess, first[excess:]))
                self._held_samples -= excess
            else:
                self._held_samples -= first.size
