"""Step 2 of the pipeline: assemble accepted samples into utterances.

The assembler knows nothing of time: the turn rules (speech_event/turns/rules.py) call ``close``
when no block arrived for the pause period. It closes an utterance by itself when it reaches the
length limit, cutting it where no word is cut in half; the rest starts the next utterance. Where it
cuts depends only on the samples, never on how they were split into blocks.

Where to cut: in the last 30 % before the limit (3 s at most), the longest quiet run wins (a
pause between words lasts longer than the dips inside a word), the latest of equally long runs,
and the cut is its middle. Quiet is within 6 dB of the quietest 20 ms there, or 20 dB below the
median; with a voice activity detector (``vad_threshold`` set) quiet is what it hears no speech in.
"""

from typing import Callable, List, Optional

import numpy as np

SEARCH_FRACTION = 0.3
SEARCH_MAX_SECONDS = 3.0
WINDOW_SECONDS = 0.02
HOP_SECONDS = 0.01
# Windows within this factor of the quietest window's energy (6 dB) are quiet, and so are those
# this far below the median (20 dB): a digitally silent dip must not make a real pause not count.
QUIET_FACTOR = 4.0
BELOW_MEDIAN = 0.01

# (audio, its rate, first sample, hop) -> for each hop from the first sample, True where a voice
# activity detector hears no speech (SileroVad.non_speech).
NonSpeech = Callable[[np.ndarray, int, int, int], np.ndarray]


def search_samples(limit: int, sample_rate: int) -> int:
    """How far back from the limit a cut is sought."""
    return min(int(SEARCH_FRACTION * limit), int(SEARCH_MAX_SECONDS * sample_rate))


def _quiet_windows(audio: np.ndarray, starts: np.ndarray, window: int) -> np.ndarray:
    energy_sums = np.concatenate(([0.0], np.cumsum(np.square(audio.astype(np.float64)))))
    energies = energy_sums[starts + window] - energy_sums[starts]
    threshold = max(energies.min() * QUIET_FACTOR, float(np.median(energies)) * BELOW_MEDIAN)
    return np.asarray(energies <= threshold + 1e-12)


def _longest_run(quiet: np.ndarray) -> Optional[range]:
    """The longest run of True (the latest of equally long ones), as window indices."""
    edges = np.flatnonzero(np.diff(np.concatenate(([0], quiet.astype(np.int8), [0]))))
    runs = [range(start, stop) for start, stop in zip(edges[::2], edges[1::2])]
    if not runs:
        return None
    longest = max(len(run) for run in runs)
    return [run for run in runs if len(run) == longest][-1]


def quiet_cut(audio: np.ndarray, limit: int, sample_rate: int, non_speech: Optional[NonSpeech] = None) -> int:
    """Where to cut ``audio`` (at least ``limit`` samples long) so the first part is <= limit."""
    window = max(1, int(WINDOW_SECONDS * sample_rate))
    hop = max(1, int(HOP_SECONDS * sample_rate))
    search = search_samples(limit, sample_rate)
    starts = np.arange(limit - search, limit - window + 1, hop)
    if starts.size == 0:
        return limit
    quiet: Optional[np.ndarray] = None
    if non_speech is not None:
        silent = non_speech(audio[:limit], sample_rate, int(starts[0]), hop)[: starts.size]
        if silent.size == starts.size and silent.any():
            quiet = silent
    if quiet is None:
        quiet = _quiet_windows(audio[:limit], starts, window)
    run = _longest_run(quiet)
    if run is None:
        return limit
    first, last = int(starts[run.start]), int(starts[run.stop - 1]) + window
    return (first + last) // 2


class UtteranceAssembler:
    """Collects accepted samples into utterances, cut at a quiet point when one reaches its length limit."""

    def __init__(
        self, sample_rate: int, max_utterance_length: float, non_speech: Optional[NonSpeech] = None
    ) -> None:
        self._sample_rate = sample_rate
        self._limit = round(max_utterance_length * sample_rate)
        self._non_speech = non_speech
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
            cut = quiet_cut(audio, self._limit, self._sample_rate, self._non_speech)
            completed.append(audio[:cut])
            self._chunks, self._length = [audio[cut:]], audio.size - cut
        return completed

    def peek(self) -> np.ndarray:
        """The utterance collected so far, kept (close() gives these same samples if nothing is added)."""
        audio = self._take_all()
        self._chunks, self._length = [audio], audio.size
        return audio

    def close(self) -> Optional[np.ndarray]:
        """End the current utterance (a pause was heard); None when nothing was collected."""
        if self._length == 0:
            return None
        return self._take_all()

    def _take_all(self) -> np.ndarray:
        audio = self._chunks[0] if len(self._chunks) == 1 else np.concatenate(self._chunks)
        self._chunks, self._length = [], 0
        return audio
