import wave
from pathlib import Path
from typing import List

import numpy as np
import pytest

from fixtures.audio import noise, speak_tones
from harness.driver import DRIVER_FORMAT, DriverConfig, WavError, play, read_wav
from speech_event import SIGNAL_TOPIC, TEXT_TOPIC
from speech_event.adapters.executors import ClockExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.config import SpeechEventConfig, load_config
from speech_event.keyvalue import ConfigError
from speech_event.messages import Float32MultiArray, String
from speech_event.node import SpeechEventNode
from speech_event.recognizers.tones import ToneRecognizer

ROOT = Path(__file__).resolve().parents[1]


def _write_wav(path: Path, samples: np.ndarray, rate: int) -> None:
    """16-bit PCM; a 2-D array is (frames, channels)."""
    with wave.open(str(path), "wb") as wav:
        wav.setnchannels(samples.shape[1] if samples.ndim == 2 else 1)
        wav.setsampwidth(2)
        wav.setframerate(rate)
        wav.writeframes(np.round(samples * 32767).astype("<i2").tobytes())


def test_the_shipped_configurations_read_as_intended() -> None:
    assert DRIVER_FORMAT.load(ROOT / "config" / "speech_event_driver.ini") == DriverConfig()
    assert load_config(ROOT / "config" / "speech_event_tests.ini") == SpeechEventConfig(verbose_mode=True)


def test_a_driver_configuration_for_two_channels_is_refused() -> None:
    with pytest.raises(ConfigError) as error:
        DRIVER_FORMAT.parse("channels 2\n", "driver.ini")
    assert (
        str(error.value)
        == "driver.ini:1: key 'channels': value '2' is out of range; allowed: 1 (the node takes mono audio)"
    )


def test_a_wav_file_is_read_as_mono_float_at_the_asked_rate(tmp_path: Path) -> None:
    t = np.arange(16000) / 16000
    left = 0.5 * np.sin(2 * np.pi * 440 * t)
    stereo = np.stack([left, left * 0.0], axis=1)
    path = tmp_path / "stereo.wav"
    _write_wav(path, stereo, 16000)
    audio = read_wav(path, 48000)
    assert audio.dtype == np.float32
    assert audio.size == 48000
    assert float(np.max(np.abs(audio))) == pytest.approx(0.25, abs=0.01)  # the two channels averaged


def test_a_file_that_is_not_wav_is_named_with_the_problem(tmp_path: Path) -> None:
    path = tmp_path / "notes.txt"
    path.write_text("not audio")
    with pytest.raises(WavError) as error:
        read_wav(path, 48000)
    assert str(error.value) == f"{path}: cannot read it as a WAV file: file does not start with RIFF id"


def test_a_recorded_session_played_by_the_driver_is_transcribed_and_silence_is_not_published(
    tmp_path: Path,
) -> None:
    rate = 48000
    silence = noise(2 * rate, -60.0, np.random.default_rng(0))
    session = np.concatenate(
        [silence, speak_tones("turn on the light", rate), silence, speak_tones("thank you", rate), silence]
    )
    path = tmp_path / "session.wav"
    _write_wav(path, session, rate)

    clock, bus = FakeClock(), InMemoryBus()
    published: List[str] = []
    blocks: List[object] = []
    bus.subscribe(TEXT_TOPIC, String, lambda message: published.append(message.data))  # type: ignore[attr-defined]
    bus.subscribe(SIGNAL_TOPIC, Float32MultiArray, blocks.append)
    node = SpeechEventNode(SpeechEventConfig(), bus, clock, ToneRecognizer(), ClockExecutor(clock))
    sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    node.start()
    config = DriverConfig(utterance_time_buffer=4800)  # 0.1 s: the two utterances stay apart
    end = play(read_wav(path, rate), config, sound_detection, clock)
    clock.advance_to(end + 2.0)
    assert published == ["turn on the light", "thank you"]
    sent = sum(message.data.size for message in blocks)  # type: ignore[attr-defined]
    assert 0 < sent < session.size / 2  # the silence was not published


def test_a_full_scale_wav_resampled_stays_within_minus_one_to_one(tmp_path: Path) -> None:
    """A square wave at full scale overshoots after resampling (Gibbs): the reader clips it, so the
    node never sees a block outside [-1, 1] from a WAV file."""
    path = tmp_path / "loud.wav"
    square = np.where(np.arange(16000) % 40 < 20, 32767, -32768).astype("<i2")
    with wave.open(str(path), "wb") as wav:
        wav.setnchannels(1)
        wav.setsampwidth(2)
        wav.setframerate(16000)
        wav.writeframes(square.tobytes())
    audio = read_wav(path, 48000)
    assert float(np.max(np.abs(audio))) == 1.0
