"""Whisper's log-mel features (whisper.audio.log_mel_spectrogram) in numpy, for one 30 s window.

16 kHz audio followed by 30 s of silence (as whisper's transcribe pads it); a periodic Hann
window of 400 samples, hop 160, frames centred by reflecting n_fft / 2 samples at each end; the
power spectrum, the last frame dropped; Slaney mel filters (librosa's, as whisper's
mel_filters.npz holds them); log10 of at least 1e-10; floored at 8 below the maximum over the
whole padded signal; (x + 4) / 4. The window's first 3000 frames are the encoder's input.
"""

import numpy as np

from speech_event.asr.features import mel_filterbank

SAMPLE_RATE = 16000
N_FFT = 400
HOP = 160
CHUNK_SAMPLES = 30 * SAMPLE_RATE
CHUNK_FRAMES = CHUNK_SAMPLES // HOP


def whisper_log_mel(audio: np.ndarray, mel_bands: int) -> np.ndarray:
    """[mel_bands, 3000] features of the first 30 s of ``audio`` (16 kHz)."""
    signal = np.concatenate([np.asarray(audio, dtype=np.float32), np.zeros(CHUNK_SAMPLES, np.float32)])
    padded = np.pad(signal.astype(np.float64), N_FFT // 2, mode="reflect")
    frames = 1 + (padded.size - N_FFT) // HOP
    window = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(N_FFT) / N_FFT)  # torch.hann_window: periodic
    starts = np.arange(frames - 1) * HOP  # the last frame is dropped, as whisper drops it
    framed = padded[starts[:, None] + np.arange(N_FFT)[None, :]] * window
    power = np.square(np.abs(np.fft.rfft(framed, axis=1)))
    mel = mel_filterbank(SAMPLE_RATE, N_FFT, mel_bands).astype(np.float32).astype(np.float64) @ power.T
    log_spec = np.log10(np.maximum(mel, 1e-10))
    log_spec = np.maximum(log_spec, log_spec.max() - 8.0)
    features: np.ndarray = ((log_spec[:, :CHUNK_FRAMES] + 4.0) / 4.0).astype(np.float32)
    return features
