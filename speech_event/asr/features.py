"""NeMo's log-mel features (AudioToMelSpectrogramPreprocessor at inference) in numpy.

16 kHz audio; pre-emphasis; 25 ms symmetric Hann window zero-padded to n_fft = 512, 10 ms stride,
frames centred (the signal padded by n_fft / 2 zeros each side); power spectrum; 80 Slaney mel
bands from 0 to 8 kHz; log(x + 2**-24); each band normalised over the utterance (mean, and the
unbiased standard deviation + 1e-5). No dither at inference, no padding of the frame count.
"""

from dataclasses import dataclass
from functools import lru_cache

import numpy as np


@dataclass(frozen=True)
class FeatureSettings:
    sample_rate: int = 16000
    window_seconds: float = 0.025
    stride_seconds: float = 0.01
    n_fft: int = 512
    mel_bands: int = 80
    preemphasis: float = 0.97
    normalize: str = "per_feature"  # or "none"


_LOG_GUARD = 2.0**-24
_STD_GUARD = 1e-5


def _hz_to_mel(hz: np.ndarray) -> np.ndarray:
    """The Slaney mel scale (librosa's default): linear below 1 kHz, logarithmic above."""
    linear = hz / (200.0 / 3)
    log_region = 15.0 + np.log(np.maximum(hz, 1e-10) / 1000.0) / (np.log(6.4) / 27.0)
    return np.where(hz >= 1000.0, log_region, linear)


def _mel_to_hz(mel: np.ndarray) -> np.ndarray:
    linear = mel * (200.0 / 3)
    log_region = 1000.0 * np.exp((np.log(6.4) / 27.0) * (mel - 15.0))
    return np.where(mel >= 15.0, log_region, linear)


@lru_cache(maxsize=8)
def mel_filterbank(sample_rate: int, n_fft: int, bands: int) -> np.ndarray:
    """[bands, n_fft // 2 + 1] triangular filters, Slaney-normalised (as librosa.filters.mel)."""
    fft_hz = np.linspace(0.0, sample_rate / 2, n_fft // 2 + 1)
    edges = _mel_to_hz(
        np.linspace(_hz_to_mel(np.array(0.0)), _hz_to_mel(np.array(sample_rate / 2)), bands + 2)
    )
    widths = np.diff(edges)
    ramps = edges[:, None] - fft_hz[None, :]
    lower = -ramps[:-2] / widths[:-1, None]
    upper = ramps[2:] / widths[1:, None]
    weights = np.maximum(0.0, np.minimum(lower, upper))
    weights *= (2.0 / (edges[2 : bands + 2] - edges[:bands]))[:, None]
    return weights.astype(np.float64)


def log_mel(audio: np.ndarray, settings: FeatureSettings) -> np.ndarray:
    """[mel_bands, frames] log-mel energies, before normalisation."""
    signal = np.asarray(audio, dtype=np.float64)
    if settings.preemphasis:
        signal = np.concatenate([signal[:1], signal[1:] - settings.preemphasis * signal[:-1]])
    window_length = round(settings.window_seconds * settings.sample_rate)
    hop = round(settings.stride_seconds * settings.sample_rate)
    n_fft = settings.n_fft
    padded = np.pad(signal, n_fft // 2)
    frames = 1 + (padded.size - n_fft) // hop
    if frames < 1:
        return np.zeros((settings.mel_bands, 0), dtype=np.float32)
    # torch.stft centres a win_length window inside the n_fft frame.
    window = np.zeros(n_fft)
    offset = (n_fft - window_length) // 2
    window[offset : offset + window_length] = np.hanning(window_length)  # symmetric, as NeMo (periodic=False)
    starts = np.arange(frames) * hop
    framed = padded[starts[:, None] + np.arange(n_fft)[None, :]] * window
    power = np.square(np.abs(np.fft.rfft(framed, n=n_fft, axis=1)))
    mel = mel_filterbank(settings.sample_rate, n_fft, settings.mel_bands) @ power.T
    return np.log(mel + _LOG_GUARD).astype(np.float32)


def valid_frames(samples: int, settings: FeatureSettings) -> int:
    """The frames NeMo counts as the utterance's (the last, mostly padding, is not one)."""
    return samples // round(settings.stride_seconds * settings.sample_rate)


def features(audio: np.ndarray, settings: FeatureSettings) -> np.ndarray:
    """[mel_bands, frames] features as the model expects them."""
    energies = log_mel(audio, settings)[:, : max(valid_frames(len(audio), settings), 0)]
    if settings.normalize == "none" or energies.shape[1] < 2:
        return energies
    mean = energies.mean(axis=1, keepdims=True)
    std = energies.std(axis=1, ddof=1, keepdims=True) + _STD_GUARD
    normalised: np.ndarray = ((energies - mean) / std).astype(np.float32)
    return normalised
