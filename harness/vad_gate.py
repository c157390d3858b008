"""Silero VAD as the driver's second gate (``vad_threshold``), for rooms where noise is loud.

The gate asks it about every chunk, so it sees the stream whole: the chunks are resampled to
16 kHz as they come and run through the model in 512-sample windows, its state carried on. A chunk
is speech when a window that ended in it, or the last window before it, reaches the threshold.
"""

from typing import List

import numpy as np
import soxr

from harness.driver import DriverConfig
from speech_event.pipeline.vad import CONTEXT, SAMPLE_RATE, WINDOW, SileroVad, silero_model_path


class VadGate:
    def __init__(self, vad: SileroVad, threshold: float, sample_rate: int) -> None:
        self._vad = vad
        self._threshold = threshold
        self._resampler = soxr.ResampleStream(sample_rate, SAMPLE_RATE, 1, dtype="float32")
        self._pending = np.zeros(0, dtype=np.float32)
        self._context = np.zeros(CONTEXT, dtype=np.float32)
        self._state = vad.initial_state()
        self._last = 0.0  # the probability of the last window

    @classmethod
    def from_config(cls, config: DriverConfig) -> "VadGate":
        return cls(SileroVad(silero_model_path()), config.vad_threshold, config.sample_rate)

    def __call__(self, chunk: np.ndarray) -> bool:
        samples = np.concatenate([self._pending, self._resampler.resample_chunk(chunk.astype(np.float32))])
        probabilities: List[float] = [self._last]
        whole = samples.size - samples.size % WINDOW
        for start in range(0, whole, WINDOW):
            window = samples[start : start + WINDOW]
            probability, self._state = self._vad.window_probability(self._context, window, self._state)
            self._context = window[-CONTEXT:]
            probabilities.append(probability)
        self._pending = samples[whole:]
        self._last = probabilities[-1]
        return max(probabilities) >= self._threshold
