"""Whisper's log-mel features (whisper.audio.log_mel_spectrogram) in numpy, for one 30 s window.

16 kHz audio followed by 30 s of silence (as whisper's transcribe pads it); a periodic Hann
window of 400 samples, hop 160, frames centred by reflecting n_fft / 2 samples at each end; the
power spectrum, the last frame dropped; Slaney mel filters (librosa's, as whisper's
mel_filters.npz holds them); log10 of at least 1e-10; floored at 8 below the maximum over the
whole padded signal; (x + 4) / 4. The window's first 3000 frames are the encoder's input.
"""

import numpy as np

from speech_event.recognizers.onnx.mel import mel_filterbank

SAMPLE_RATE = 16000
N_FFT = 400
HOP = 160
CHUNK_SAMPLES = 30 * SAMPLE_RATE
CHUNK_FRAMES = CHUNK_SAMPLES // HOP


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
    window = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(N_FFT) / N_FFT)  # torch.hann_window: periodic
    starts = np.arange(seen) * HOP
    framed = signal[starts[:, None] + np.arange(N_FFT)[None, :]] * window
    power = np.square(np.abs(np.fft.rfft(framed, axis=1)))
    filters = mel_filterbank(SAMPLE_RATE, N_FFT, mel_bands).astype(np.float32).astype(np.float64)
    log_spec = np.full((mel_bands, CHUNK_FRAMES), -10.0)  # log10 of the 1e-10 floor
    log_spec[:, :seen] = np.log10(np.maximum(filters @ power.T, 1e-10))
    log_spec = np.maximum(log_spec, log_spec.max() - 8.0)
    features: np.ndarray = ((log_spec + 4.0) / 4.0).astype(np.float32)
    return features
