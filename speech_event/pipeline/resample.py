"""Step 4 of the pipeline: bring an utterance to the recognizer's sample rate.

soxr is a proper band-limited resampler: naive interpolation would fold everything above the new
Nyquist frequency back into the speech band.
"""

import numpy as np
import soxr


def resample(audio: np.ndarray, from_rate: int, to_rate: int) -> np.ndarray:
    """``audio`` at ``to_rate`` instead of ``from_rate`` (soxr, high quality); itself when the rates match."""
    if from_rate == to_rate:
        return audio
    return np.asarray(soxr.resample(audio, from_rate, to_rate, quality="HQ"), dtype=np.float32)


class StreamResampler:
    """One growing utterance brought to another rate piece by piece (soxr's stream: the pieces
    join without seams); for the partial results of an Incremental engine."""

    def __init__(self, from_rate: int, to_rate: int) -> None:
        same = from_rate == to_rate
        self._stream = None if same else soxr.ResampleStream(from_rate, to_rate, 1, "float32", "HQ")

    def __call__(self, audio: np.ndarray) -> np.ndarray:
        """The next piece at the new rate (soxr holds back a few samples for its filter)."""
        if self._stream is None:
            return audio
        piece = self._stream.resample_chunk(np.ascontiguousarray(audio, dtype=np.float32))
        return np.asarray(piece, dtype=np.float32)
