"""The seed's driver: a soundDetection stand-in that publishes a WAV file as the robot's driver
publishes its microphone (config/speech_event_driver.ini, the seed's Table 2).

Like the robot's driver, it cuts the audio into ``chunk_size``-sample chunks; a chunk counts as
speech when any sample reaches ``speech_amplitude_threshold``; chunks within
``utterance_time_buffer`` samples of speech are published too (pre-roll and hang-over); the rest is
silence and is not published at all. Chunks go out paced in real time on the Clock it is given, so
the same code plays to the in-memory bus (tests) and to ROS (scripts/speech_event_driver.py), and
a session stored with ``audio_storage_dir`` can be played back to the node.
"""

import wave
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, List, Tuple, Union

import numpy as np

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


def speech_chunks(audio: np.ndarray, config: DriverConfig) -> List[Tuple[int, np.ndarray]]:
    """The chunks the driver publishes, with their index: speech and what is near it."""
    size = config.chunk_size
    count = -(-audio.size // size)
    padded = np.zeros(count * size, dtype=np.float32)
    padded[: audio.size] = audio
    chunks = padded.reshape(count, size)
    loud = np.max(np.abs(chunks), axis=1) >= config.speech_amplitude_threshold
    reach = -(-config.utterance_time_buffer // size)
    published = np.zeros(count, dtype=bool)
    for index in np.flatnonzero(loud):
        published[max(0, index - reach) : index + reach + 1] = True
    return [(int(index), chunks[index]) for index in np.flatnonzero(published)]


def _publishing(publisher: Publisher, message: object) -> Callable[[], None]:
    return lambda: publisher.publish(message)


def play(audio: np.ndarray, config: DriverConfig, publisher: Publisher, clock: Clock) -> float:
    """Schedule the speech chunks on ``clock``, each when it has been 'recorded'; return the end time."""
    start = clock.now()
    seconds_per_chunk = config.chunk_size / config.sample_rate
    for index, chunk in speech_chunks(audio, config):
        clock.call_at(
            start + (index + 1) * seconds_per_chunk, _publishing(publisher, Float32MultiArray(data=chunk))
        )
    return start + -(-audio.size // config.chunk_size) * seconds_per_chunk
