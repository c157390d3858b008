"""Whisper's log-mel features (whisper.audio.log_mel_spectrogram) in numpy.

A periodic Hann window of 400 samples, hop 160, frames centred by reflecting n_fft / 2 samples at
each end; the power spectrum, the last frame dropped; Slaney mel filters (librosa's, as whisper's
mel_filters.npz holds them); log10 of at least 1e-10; floored at 8 below the maximum over the
whole signal; (x + 4) / 4.

``whisper_log_mel``: one 30 s window of the recognizer, the audio followed by 30 s of silence (as
whisper's transcribe pads it); the window's first 3000 frames are the encoder's input.
``window_log_mel``: a buffer of exactly the window's length, reflected at both ends (what
transformers' WhisperFeatureExtractor computes, and Smart Turn reads).
"""

import numpy as np

from speech_event.recognizers.onnx.mel import mel_filterbank

SAMPLE_RATE = 16000
N_FFT = 400
HOP = 160
CHUNK_SAMPLES = 30 * SAMPLE_RATE
CHUNK_FRAMES = CHUNK_SAMPLES // HOP
LOG_FLOOR = -10.0  # log10 of the 1e-10 floor


def _log_power(signal: np.ndarray, frames: int, mel_bands: int) -> np.ndarray:
    """[mel_bands, frames] log10 mel power of the first ``frames`` frames of ``signal``, which is
    already padded by n_fft / 2 samples before its first frame's centre."""
    window = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(N_FFT) / N_FFT)  # torch.hann_window: periodic
    starts = np.arange(frames) * HOP
    framed = signal[starts[:, None] + np.arange(N_FFT)[None, :]] * window
    power = np.square(np.abs(np.fft.rfft(framed, axis=1)))
    filters = mel_filterbank(SAMPLE_RATE, N_FFT, mel_bands).astype(np.float32).astype(np.float64)
    return np.asarray(np.log10(np.maximum(filters @ power.T, 1e-10)))


def _scaled(log_spec: np.ndarray) -> np.ndarray:
    log_spec = np.maximum(log_spec, log_spec.max() - 8.0)
    return np.asarray((log_spec + 4.0) / 4.0, dtype=np.float32)


def whisper_log_mel(audio: np.ndarray, mel_bands: int) -> np.ndarray:
    """[mel_bands, 3000] features of the first 30 s of ``audio`` (16 kHz)."""
    audio = np.asarray(audio, dtype=np.float32)[:CHUNK_SAMPLES]
    # Frames whose window lies wholly in the silence after the audio have no power at all: only
    # the frames that see the audio are computed, the others are the floor (as whisper finds them).
    seen = min(CHUNK_FRAMES, (audio.size + N_FFT // 2) // HOP + 1)
    signal = np.zeros(seen * HOP + N_FFT, np.float64)
    signal[N_FFT // 2 : N_FFT // 2 + audio.size] = audio
    # whisper's reflect padding at the start (the end is the padding's silence, reflected)
    signal[: N_FFT // 2] = signal[N_FFT : N_FFT // 2 : -1]
    log_spec = np.full((mel_bands, CHUNK_FRAMES), LOG_FLOOR)
    log_spec[:, :seen] = _log_power(signal, seen, mel_bands)
    return _scaled(log_spec)


def window_log_mel(buffer: np.ndarray, mel_bands: int) -> np.ndarray:
    """[mel_bands, len(buffer) / 160] features of exactly ``buffer`` (16 kHz), reflected at both
    ends, its last frame dropped."""
    signal = np.pad(np.asarray(buffer, dtype=np.float64), N_FFT // 2, mode="reflect")
    return _scaled(_log_power(signal, buffer.size // HOP, mel_bands))
