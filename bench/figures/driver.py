"""The driver's cost (python -m bench.figures.driver): what one microphone chunk costs, and Silero's gate.

(a) the amplitude gate (harness/gate.py) on 10 minutes of 48 kHz audio fed as 1024-sample chunks,
    half speech, half room noise: microseconds per chunk and the real-time factor;
(b) the whole microphone path per chunk after PortAudio: a stereo block mixed down, resampled
    from 44.1 to 48 kHz (soxr's stream), gated: microseconds per chunk;
(c) the Silero VAD gate (harness/vad_gate.py: every chunk resampled to 16 kHz and run through the
    model in 512-sample windows) on 2 minutes of the same audio: real-time factor, on this
    machine's cores (onnxruntime limited to one thread, as the driver runs it).
"""

import time
from typing import List

import numpy as np
import soxr

from fixtures.audio import noise, speak_tones
from harness.driver import DriverConfig, gate_settings
from harness.gate import SpeechGate
from harness.vad_gate import VadGate

RATE = 48000
CHUNK = 1024


def _session(seconds: float) -> np.ndarray:
    rng = np.random.default_rng(0)
    speech = speak_tones("turn on the light in the kitchen please", RATE)
    parts: List[np.ndarray] = []
    while sum(part.size for part in parts) < seconds * RATE:
        parts += [speech, noise(speech.size, -40.0, rng)]
    return np.concatenate(parts)[: int(seconds * RATE)].astype(np.float32)


def _gate_cost(audio: np.ndarray, gate: SpeechGate) -> float:
    began = time.perf_counter()
    for start in range(0, audio.size, CHUNK):
        gate.feed(audio[start : start + CHUNK])
    return time.perf_counter() - began


def main() -> None:
    config = DriverConfig()
    audio = _session(600.0)
    chunks = audio.size // CHUNK
    took = _gate_cost(audio, SpeechGate(gate_settings(config)))
    per_chunk = 1e6 * took / chunks
    print(
        f"(a) amplitude gate: {per_chunk:.1f} us per {CHUNK}-sample chunk, real-time factor {took / 600:.5f}"
    )

    stereo = np.stack([audio[: 60 * 44100], np.zeros(60 * 44100, dtype=np.float32)], axis=1)
    resampler = soxr.ResampleStream(44100, RATE, 1, dtype="float32")
    gate = SpeechGate(gate_settings(config))
    began = time.perf_counter()
    for start in range(0, stereo.shape[0], CHUNK):
        block = stereo[start : start + CHUNK]
        gate.feed(resampler.resample_chunk(np.ascontiguousarray(block.mean(axis=1))))
    took = time.perf_counter() - began
    per_chunk = 1e6 * took / (stereo.shape[0] / CHUNK)
    print(f"(b) microphone path (stereo 44.1 kHz -> mono 48 kHz, gate): {per_chunk:.1f} us per chunk")

    short = audio[: 120 * RATE]
    vad_gate = SpeechGate(gate_settings(config), VadGate.from_config(DriverConfig(vad_threshold=0.5)))
    took = _gate_cost(short, vad_gate)
    per_chunk = 1e6 * took / (short.size / CHUNK)
    print(f"(c) Silero VAD gate: real-time factor {took / 120:.4f} ({per_chunk:.0f} us per chunk)")


if __name__ == "__main__":
    main()
