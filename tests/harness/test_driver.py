import os
import subprocess
import sys
import threading
import wave
from pathlib import Path
from typing import Callable, List, Tuple

import numpy as np
import pytest

from fixtures.audio import noise, speak_tones
from fixtures.paths import ROOT
from harness.driver import DRIVER_FORMAT, AudioFileError, DriverConfig, play, read_audio
from speech_event import SIGNAL_TOPIC, TEXT_TOPIC
from speech_event.adapters.executors import ClockExecutor
from speech_event.adapters.fake_clock import FakeClock, FakeTimer
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.config import SpeechEventConfig, load_config
from speech_event.errors import ConfigError
from speech_event.messages import Float32MultiArray, String
from speech_event.node import SpeechEventNode
from speech_event.recognizers.tones import ToneRecognizer


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


def test_the_robots_spellings_and_mode_are_read() -> None:
    config = DRIVER_FORMAT.parse(
        "chunkSize 512\nsampleRate 16000\nspeechAmplitudeThreshold 0.2\nutteranceTimeBuffer 800\nmode FILE\n",
        "driver.ini",
    )
    assert config == DriverConfig(
        chunk_size=512,
        sample_rate=16000,
        speech_amplitude_threshold=0.2,
        utterance_time_buffer=800,
        mode="file",
    )


def test_a_driver_configuration_with_an_unknown_mode_says_what_is_allowed() -> None:
    with pytest.raises(ConfigError) as error:
        DRIVER_FORMAT.parse("mode speaker\n", "driver.ini")
    assert (
        str(error.value)
        == "driver.ini:1: key 'mode': value 'speaker' is not one of the choices; allowed: mic or file"
    )


def test_a_wav_file_is_read_as_mono_float_at_the_asked_rate(tmp_path: Path) -> None:
    t = np.arange(16000) / 16000
    left = 0.5 * np.sin(2 * np.pi * 440 * t)
    stereo = np.stack([left, left * 0.0], axis=1)
    path = tmp_path / "stereo.wav"
    _write_wav(path, stereo, 16000)
    audio = read_audio(path, 48000)
    assert audio.dtype == np.float32
    assert audio.size == 48000
    assert float(np.max(np.abs(audio))) == pytest.approx(0.25, abs=0.01)  # the two channels averaged


def test_a_file_that_is_not_wav_is_named_with_the_problem(tmp_path: Path) -> None:
    path = tmp_path / "notes.wav"
    path.write_text("not audio")
    with pytest.raises(AudioFileError) as error:
        read_audio(path, 48000)
    assert str(error.value) == f"{path}: cannot read it as a WAV file: file does not start with RIFF id"
    other = tmp_path / "notes.txt"
    other.write_text("not audio")
    with pytest.raises(AudioFileError) as error:
        read_audio(other, 48000)
    assert str(error.value) == (
        f"{other}: cannot read it as audio (Error opening {str(other)!r}: Format not recognised.); "
        "allowed: what libsndfile reads (WAV, FLAC, OGG, ...)"
    )


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
    end = play(read_audio(path, rate), config, sound_detection, clock)
    clock.advance_to(end + 2.0)
    assert published == ["turn on the light", "thank you"]
    sent = sum(message.data.size for message in blocks)  # type: ignore[attr-defined]
    assert 0 < sent < session.size / 2  # the silence was not published


class _LateThreadsClock:
    """A wall clock on a busy machine: each timer is a thread of its own, and the threads of timers
    that are due together run in any order (here: the last set runs first)."""

    def __init__(self) -> None:
        self._now = 0.0
        self._timers: List[Tuple[float, Callable[[], None], FakeTimer]] = []

    def now(self) -> float:
        return self._now

    def call_at(self, when: float, callback: Callable[[], None]) -> FakeTimer:
        timer = FakeTimer(callback)
        self._timers.append((when, callback, timer))
        return timer

    def advance_to(self, when: float) -> None:
        self._now = when
        while True:
            due = [entry for entry in self._timers if entry[0] <= when]
            if not due:
                return
            for entry in reversed(due):
                self._timers.remove(entry)
                if not entry[2].cancelled:
                    entry[1]()


def test_the_driver_publishes_a_files_blocks_in_order_when_its_timers_run_out_of_order() -> None:
    """Each block 21 ms after the one before: on a busy machine their timer threads ran late and
    together, and the node got them shuffled (pocketsphinx's texts changed from run to run)."""
    rng = np.random.default_rng(7)
    audio = (0.5 * rng.standard_normal(48000)).astype(np.float32)  # loud throughout: all published
    clock, sent = _LateThreadsClock(), _Recorder()
    published = threading.Event()
    end = play(audio, DriverConfig(), sent, clock, published=published)
    assert not published.is_set()
    clock.advance_to(end + 1.0)  # every block due at once, as after a stall
    assert published.is_set()
    assert np.array_equal(np.concatenate(sent.blocks), audio)


class _Recorder:
    def __init__(self) -> None:
        self.blocks: List[np.ndarray] = []

    def publish(self, message: object) -> None:
        self.blocks.append(np.asarray(message.data))  # type: ignore[attr-defined]


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
    audio = read_audio(path, 48000)
    assert float(np.max(np.abs(audio))) == 1.0


def _driver_command(*arguments: str) -> "subprocess.CompletedProcess[str]":
    return subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "speech_event_driver.py"), *arguments],
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_the_driver_plays_a_flac_file_to_the_node_on_the_in_memory_bus(tmp_path: Path) -> None:
    import soundfile

    rate = 48000
    session = np.concatenate([np.zeros(rate // 2), speak_tones("open the door", rate), np.zeros(rate // 2)])
    soundfile.write(str(tmp_path / "session.flac"), session, rate)
    result = _driver_command(
        "-c",
        str(ROOT / "config" / "speech_event_driver.ini"),
        str(tmp_path / "session.flac"),
        "--transport",
        "memory",
        "--recognizer",
        "fake",
    )
    assert (result.returncode, result.stdout, result.stderr) == (
        0,
        "/speechEvent/text: 'open the door'\n",
        "",
    )


def test_the_driver_plays_a_scenarios_speech_and_outage_on_the_in_memory_bus(tmp_path: Path) -> None:
    (tmp_path / "node.ini").write_text("health_check_period 1.0\n")
    result = _driver_command(
        "-c",
        str(ROOT / "config" / "speech_event_driver.ini"),
        "scenarios/outage_then_recovery.toml",
        "--transport",
        "memory",
        "--recognizer",
        "fake",
        "--node-config",
        str(tmp_path / "node.ini"),
    )
    lines = result.stdout.splitlines()
    assert lines[-1] == "/speechEvent/text: 'i am back'", result.stderr
    assert set(lines[:-1]) == {"/speechEvent/text: 'Error: soundDetection is down'"}
    assert (
        2 <= len(lines[:-1]) <= 3
    )  # checks at 1 and 2 s of the 2.5 s outage (wall clock: one more may fall in)


def test_mode_file_without_a_file_is_one_clear_error(tmp_path: Path) -> None:
    (tmp_path / "driver.ini").write_text("mode file\n")
    result = _driver_command("-c", str(tmp_path / "driver.ini"), "--transport", "memory")
    assert (result.returncode, result.stderr) == (
        2,
        f"speech_event_driver: error: {tmp_path / 'driver.ini'}: mode file needs a SOURCE file on the command line\n",
    )
