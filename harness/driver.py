"""The seed's driver: a soundDetection stand-in (config/speech_event_driver.ini, the seed's Table 2).

Its configuration, its audio files, and the playing of a file; the microphone is
harness/microphone.py, the command line harness/driver_node.py.

Like the robot's driver, it publishes only speech: harness/gate.py says exactly what (chunks with
a sample at ``speech_amplitude_threshold``, ``utterance_time_buffer`` samples around them). The
pieces go out paced in real time on the Clock it is given, so the same code plays to the
in-memory bus (tests) and to ROS (scripts/speech_event_driver.py), and a session stored with
``audio_storage_dir`` can be played back to the node.
"""

import threading
import wave
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator, Optional, Tuple, Union

import numpy as np

from harness.gate import GateSettings, Piece, SpeechGate
from speech_event.keyvalue import KeyRule, KeyValueFormat, choice, number, seconds, text
from speech_event.messages import Float32MultiArray
from speech_event.pipeline.resample import resample
from speech_event.ports import Clock, Publisher


@dataclass(frozen=True)
class DriverConfig:
    channels: int = 1  # captured from the microphone, mixed down to the one channel published
    chunk_size: int = 1024
    sample_rate: int = 48000  # published; must be the node's sample_rate
    speech_amplitude_threshold: float = 0.1
    utterance_time_buffer: int = 48000
    # The robot's driver: mic (the default input device, or ``device``) or file (the FILE argument).
    mode: str = "mic"
    device: str = ""  # an input device: its index, or part of its name; empty: the default one
    # Silero VAD as a second gate in noisy rooms: a loud chunk is speech only when the speech
    # probability around it reaches this; 0: the amplitude alone decides (the seed's gate).
    vad_threshold: float = 0.0
    retry_period: float = 2.0  # seconds between tries to open a missing or lost device


DRIVER_FORMAT = KeyValueFormat(
    DriverConfig,
    {
        "channels": KeyRule(number(int, 1, 64), "an integer number of channels from 1 to 64"),
        "chunk_size": KeyRule(number(int, 64, 65536), "an integer number of samples from 64 to 65536"),
        "sample_rate": KeyRule(number(int, 8000, 192000), "an integer number of Hz from 8000 to 192000"),
        "speech_amplitude_threshold": KeyRule(number(float, 0.0, 1.0), "a number from 0 to 1"),
        "utterance_time_buffer": KeyRule(number(int, 0, 10**7), "an integer number of samples, 0 or more"),
        "mode": KeyRule(choice("mic", "file"), "mic or file"),
        "device": KeyRule(text, "an input device's index or part of its name; empty: the default one"),
        "vad_threshold": KeyRule(number(float, 0.0, 1.0), "a speech probability from 0 to 1; 0: no VAD"),
        "retry_period": seconds(0.1, 600.0),
    },
)


class AudioFileError(Exception):
    """A file the driver cannot read as audio."""


_PCM_SCALE = {1: 128.0, 2: 32768.0, 4: 2147483648.0}


def read_audio(path: Union[str, Path], sample_rate: int) -> np.ndarray:
    """An audio file as mono float32 in [-1, 1] at ``sample_rate``: PCM WAV with the standard
    library, anything else libsndfile reads (FLAC, OGG, ...) through soundfile."""
    mono, rate = _read_wav(path) if str(path).lower().endswith(".wav") else _read_soundfile(path)
    # Resampling full-scale audio overshoots (to about 1.05): clipped here, as the node accepts
    # only [-1, 1] and would otherwise clip every such block itself.
    return np.asarray(np.clip(resample(mono.astype(np.float32), rate, sample_rate), -1.0, 1.0))


def _read_wav(path: Union[str, Path]) -> Tuple[np.ndarray, int]:
    try:
        with wave.open(str(path), "rb") as wav:
            width, channels, rate = wav.getsampwidth(), wav.getnchannels(), wav.getframerate()
            frames = wav.readframes(wav.getnframes())
    except (OSError, EOFError, wave.Error) as problem:
        raise AudioFileError(f"{path}: cannot read it as a WAV file: {problem}") from None
    if width not in _PCM_SCALE:
        raise AudioFileError(f"{path}: {8 * width}-bit samples; allowed: 8, 16 or 32-bit PCM")
    if width == 1:  # 8-bit WAV is unsigned
        samples = np.frombuffer(frames, dtype=np.uint8).astype(np.float32) - 128.0
    else:
        samples = np.frombuffer(frames, dtype=f"<i{width}").astype(np.float32)
    return (samples / _PCM_SCALE[width]).reshape(-1, channels).mean(axis=1), rate


def _read_soundfile(path: Union[str, Path]) -> Tuple[np.ndarray, int]:
    try:
        import soundfile
    except (ImportError, OSError) as problem:  # not installed, or no libsndfile
        raise AudioFileError(
            f"{path}: files other than WAV need soundfile (pip install soundfile): {problem}"
        ) from None
    try:
        samples, rate = soundfile.read(str(path), dtype="float32", always_2d=True)
    except (RuntimeError, OSError) as problem:  # soundfile.LibsndfileError is a RuntimeError
        raise AudioFileError(
            f"{path}: cannot read it as audio ({problem}); "
            "allowed: what libsndfile reads (WAV, FLAC, OGG, ...)"
        ) from None
    return samples.mean(axis=1), int(rate)


def gate_settings(config: DriverConfig) -> GateSettings:
    return GateSettings(config.chunk_size, config.speech_amplitude_threshold, config.utterance_time_buffer)


def play(
    audio: np.ndarray,
    config: DriverConfig,
    publisher: Publisher,
    clock: Clock,
    gate: Optional[SpeechGate] = None,
    published: Optional[threading.Event] = None,
) -> float:
    """Publish each piece on ``clock`` when its last sample has been 'recorded', in order; return
    the end time. ``gate``: another than the amplitude gate of ``config`` (with Silero VAD);
    ``published``: set once the last piece is out (a busy machine's timers run late)."""
    start = clock.now()
    gate = gate or SpeechGate(gate_settings(config))
    pieces = iter(gate.feed(audio) + gate.finish())
    _publish_in_turn(pieces, start, config.sample_rate, publisher, clock, published or threading.Event())
    return start + audio.size / config.sample_rate


def _publish_in_turn(
    pieces: Iterator[Piece],
    start: float,
    sample_rate: int,
    publisher: Publisher,
    clock: Clock,
    published: threading.Event,
) -> None:
    """One timer at a time, each piece's setting the next: on the wall clock every timer is a thread
    of its own, and threads set all at once ran out of order on a busy machine (blocks 21 ms apart
    reached the node shuffled, and its texts changed from run to run)."""
    following = next(pieces, None)
    if following is None:
        published.set()
        return
    first, piece = following

    def publish() -> None:
        publisher.publish(Float32MultiArray(data=piece))
        _publish_in_turn(pieces, start, sample_rate, publisher, clock, published)

    clock.call_at(start + (first + piece.size) / sample_rate, publish)
