"""Step 2 of the pipeline: assemble accepted samples into utterances.

The assembler knows nothing of time: the node calls ``close`` when no block arrived for the pause
period. It closes an utterance by itself when it reaches the length limit, cutting at the quietest
point near the limit so that no sound is cut in half; the rest starts the next utterance. Where it
cuts depends only on the samples, never on how they were split into blocks.
"""

from typing import List, Optional

import numpy as np

# The cut is sought in the last part of an utterance that reached the limit...
SEARCH_SECONDS = 1.0
# ...as the centre of the quietest window of this length, stepped by HOP_SECONDS. Longer than the
# short dips inside a word, shorter than a pause between words.
WINDOW_SECONDS = 0.05
HOP_SECONDS = 0.01
# Windows within this factor of the quietest energy count as equally quiet; the latest one wins so
# utterances stay as long as the limit allows.
QUIET_FACTOR = 2.0


def quietest_cut(audio: np.ndarray, limit: int, sample_rate: int) -> int:
    """Where to cut ``audio`` (at least ``limit`` samples long) so the first part is <= limit."""
    window = max(1, int(WINDOW_SECONDS * sample_rate))
    hop = max(1, int(HOP_SECONDS * sample_rate))
    search = min(int(SEARCH_SECONDS * sample_rate), limit // 2)
    first_start = limit - search
    starts = np.arange(first_start, limit - window + 1, hop)
    if starts.size == 0:
        return limit
    energy_sums = np.concatenate(([0.0], np.cumsum(np.square(audio[:limit].astype(np.float64)))))
    energies = energy_sums[starts + window] - energy_sums[starts]
    quiet = np.flatnonzero(energies <= energies.min() * QUIET_FACTOR + 1e-12)
    return int(starts[quiet[-1]] + window // 2)


class UtteranceAssembler:
    def __init__(self, sample_rate: int, max_utterance_length: float) -> None:
        self._sample_rate = sample_rate
        self._limit = round(max_utterance_length * sample_rate)
        self._chunks: List[np.ndarray] = []
        self._length = 0

    @property
    def pending_samples(self) -> int:
        return self._length

    def add(self, samples: np.ndarray) -> List[np.ndarray]:
        """Append samples; return the utterances that reached the length limit, in order."""
        self._chunks.append(samples)
        self._length += samples.size
        completed: List[np.ndarray] = []
        while self._length >= self._limit:
            audio = self._take_all()
            cut = quietest_cut(audio, self._limit, self._sample_rate)
            completed.append(audio[:cut])
            self._chunks, self._length = [audio[cut:]], audio.size - cut
        return completed

    def close(self) -> Optional[np.ndarray]:
        """End the current utterance (a pause was heard); None when nothing was collected."""
        if self._length == 0:
            return None
        return self._take_all()

    def _take_all(self) -> np.ndarray:
        audio = self._chunks[0] if len(self._chunks) == 1 else np.concatenate(self._chunks)
        self._chunks, self._length = [], 0
        return audio
