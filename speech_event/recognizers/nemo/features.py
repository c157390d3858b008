"""NeMo's log-mel features (AudioToMelSpectrogramPreprocessor at inference) in numpy.

16 kHz audio; pre-emphasis; 25 ms symmetric Hann window zero-padded to n_fft = 512, 10 ms stride,
frames centred (the signal padded by n_fft / 2 zeros each side); power spectrum; 80 Slaney mel
bands from 0 to 8 kHz; log(x + 2**-24); each band normalised over the utterance (mean, and the
unbiased standard deviation + 1e-5). No dither at inference, no padding of the frame count.
"""

from dataclasses import dataclass

import numpy as np

from speech_event.recognizers.onnx.mel import mel_filterbank


@dataclass(frozen=True)
class FeatureSettings:
    """NeMo's preprocessor settings that matter at inference; the defaults are the robot's models'."""

    sample_rate: int = 16000
    window_seconds: float = 0.025
    stride_seconds: float = 0.01
    n_fft: int = 512
    mel_bands: int = 80
    preemphasis: float = 0.97
    normalize: str = "per_feature"  # or "none"


_LOG_GUARD = 2.0**-24
_STD_GUARD = 1e-5


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
