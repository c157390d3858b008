"""The seed's driver: a soundDetection stand-in that publishes a WAV file as the robot's driver
publishes its microphone (config/speech_event_driver.ini, the seed's Table 2).

Like the robot's driver, it publishes only speech: harness/gate.py says exactly what (chunks with
a sample at ``speech_amplitude_threshold``, ``utterance_time_buffer`` samples around them). The
pieces go out paced in real time on the Clock it is given, so the same code plays to the
in-memory bus (tests) and to ROS (scripts/speech_event_driver.py), and a session stored with
``audio_storage_dir`` can be played back to the node.
"""

import wave
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, List, Union

import numpy as np

from harness.gate import GateSettings, Piece, SpeechGate
from speech_event.keyvalue import KeyRule, KeyValueFormat, number
from speech_event.messages import Float32MultiArray
from speech_event.ports import Clock, Publisher
from speech_event.resample import resample


@dataclass(frozen=True)
class DriverConfig:
    channels: int = 1
    chunk_size: int = 1024
    sample_rate: int = 48000
    speech_amplitude_threshold: float = 0.1
    utterance_time_buffer: int = 48000


DRIVER_FORMAT = KeyValueFormat(
    DriverConfig,
    {
        "channels": KeyRule(number(int, 1, 1), "1 (the node takes mono audio)"),
        "chunk_size": KeyRule(number(int, 64, 65536), "an integer number of samples from 64 to 65536"),
        "sample_rate": KeyRule(number(int, 8000, 192000), "an integer number of Hz from 8000 to 192000"),
        "speech_amplitude_threshold": KeyRule(number(float, 0.0, 1.0), "a number from 0 to 1"),
        "utterance_time_buffer": KeyRule(number(int, 0, 10**7), "an integer number of samples, 0 or more"),
    },
)


class WavError(Exception):
    """A file the driver cannot read as audio."""


_PCM_SCALE = {1: 128.0, 2: 32768.0, 4: 2147483648.0}


def read_wav(path: Union[str, Path], sample_rate: int) -> np.ndarray:
    """A PCM WAV file as mono float32 in [-1, 1] at ``sample_rate``."""
    try:
        with wave.open(str(path), "rb") as wav:
            width, channels, rate = wav.getsampwidth(), wav.getnchannels(), wav.getframerate()
            frames = wav.readframes(wav.getnframes())
    except (OSError, EOFError, wave.Error) as problem:
        raise WavError(f"{path}: cannot read it as a WAV file: {problem}") from None
    if width not in _PCM_SCALE:
        raise WavError(f"{path}: {8 * width}-bit samples; allowed: 8, 16 or 32-bit PCM")
    if width == 1:  # 8-bit WAV is unsigned
        samples = np.frombuffer(frames, dtype=np.uint8).astype(np.float32) - 128.0
    else:
        samples = np.frombuffer(frames, dtype=f"<i{width}").astype(np.float32)
    mono = (samples / _PCM_SCALE[width]).reshape(-1, channels).mean(axis=1)
    # Resampling full-scale audio overshoots (to about 1.05): clipped here, as the node accepts
    # only [-1, 1] and would otherwise clip every such block itself.
    return np.asarray(np.clip(resample(mono.astype(np.float32), rate, sample_rate), -1.0, 1.0))


def gate_settings(config: DriverConfig) -> GateSettings:
    return GateSettings(config.chunk_size, config.speech_amplitude_threshold, config.utterance_time_buffer)


def speech_pieces(audio: np.ndarray, config: DriverConfig) -> List[Piece]:
    """What the driver publishes of ``audio``: its speech, with the buffer around it (harness/gate.py)."""
    gate = SpeechGate(gate_settings(config))
    return gate.feed(audio) + gate.finish()


def _publishing(publisher: Publisher, message: object) -> Callable[[], None]:
    return lambda: publisher.publish(message)


def play(audio: np.ndarray, config: DriverConfig, publisher: Publisher, clock: Clock) -> float:
    """Schedule each published piece on ``clock`` when its last sample has been 'recorded'; return
    the end time."""
    start = clock.now()
    for first, piece in speech_pieces(audio, config):
        clock.call_at(
            start + (first + piece.size) / config.sample_rate,
            _publishing(publisher, Float32MultiArray(data=piece)),
        )
    return start + audio.size / config.sample_rate
