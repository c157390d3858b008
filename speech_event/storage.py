"""Keeps each utterance as a WAV file when ``audio_storage_dir`` is set, for replay and debugging."""

import wave
from pathlib import Path

import numpy as np


class UtteranceStore:
    def __init__(self, directory: str, sample_rate: int) -> None:
        self._directory = Path(directory)
        self._sample_rate = sample_rate
        self._directory.mkdir(parents=True, exist_ok=True)

    def save(self, index: int, clock_time: float, audio: np.ndarray) -> Path:
        path = self._directory / f"utterance_{index:05d}_{clock_time:.3f}.wav"
        pcm = np.round(np.clip(audio, -1.0, 1.0) * 32767.0).astype("<i2")
        with wave.open(str(path), "wb") as out:
            out.setnchannels(1)
            out.setsampwidth(2)
            out.setframerate(self._sample_rate)
            out.writeframes(pcm.tobytes())
        return path
