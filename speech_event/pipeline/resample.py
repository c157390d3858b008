"""Step 3 of the pipeline: bring an utterance to the recognizer's sample rate.

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
