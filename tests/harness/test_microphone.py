"""The driver's microphone path (issue 9, item 1).

For real: PortAudio (libportaudio2, through sounddevice) captures an ALSA device of the test's own,
defined in $HOME/.asoundrc: ALSA's ``file`` plugin reading the speech from a raw file (float32,
interleaved) over its ``null`` device. That device is not paced like a sound card (it delivers
as fast as it is read), which the driver takes as it comes. A device unplugged mid-run cannot be
made so; that case runs against a stand-in for sounddevice whose stream stops.
"""

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any, Dict, List, Optional

import numpy as np
import pytest

from fixtures.audio import speak_tones
from fixtures.paths import ROOT
from harness.driver import DriverConfig
from harness.microphone import Microphone, MicrophoneError, find_device

DRIVER = ROOT / "scripts" / "speech_event_driver.py"
RATE = 48000
ASOUNDRC = """
pcm.speechfile {{
    type file
    slave.pcm "null"
    file "/dev/null"
    infile "{infile}"
    format "raw"
    hint {{ show on description "speech from a file" }}
}}
"""


def _virtual_microphone(home: Path, channels: List[np.ndarray]) -> None:
    """$HOME/.asoundrc with device 'speechfile' that captures ``channels`` (interleaved), then silence."""
    frames = np.stack(channels, axis=1)
    frames = np.concatenate([frames, np.zeros((3 * RATE, len(channels)))])
    (home / "speech.raw").write_bytes(frames.astype("<f4").tobytes())
    (home / ".asoundrc").write_text(ASOUNDRC.format(infile=home / "speech.raw"))


def _ignoring_ctrl_c() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _driver(home: Path, config: str) -> "subprocess.Popen[str]":
    """The driver on the microphone, started with SIGINT ignored as a shell starts a background job
    (a CI runner's, ``cmd &`` in a script): SIGINT must stop it all the same."""
    (home / "driver.ini").write_text(config)
    return subprocess.Popen(
        [
            sys.executable,
            str(DRIVER),
            "-c",
            str(home / "driver.ini"),
            "--transport",
            "memory",
            "--recognizer",
            "fake",
        ],
        cwd=ROOT,
        env={**os.environ, "HOME": str(home), "PYTHONPATH": str(ROOT)},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=_ignoring_ctrl_c,
    )


def _read_until(stream: Any, wanted: str, timeout: float = 30.0) -> List[str]:
    """Lines of ``stream`` up to the first that is ``wanted`` (read on a thread: no hang)."""
    lines: List[str] = []
    found = threading.Event()

    def read() -> None:
        for line in stream:
            lines.append(line.rstrip("\n"))
            if lines[-1] == wanted:
                found.set()
                return

    threading.Thread(target=read, daemon=True).start()
    assert found.wait(timeout), f"no {wanted!r} in {lines}"
    return lines


def _stop(driver: "subprocess.Popen[str]") -> str:
    driver.send_signal(signal.SIGINT)
    try:
        _, stderr = driver.communicate(timeout=30)
    finally:
        driver.kill()
    return stderr


SPEECH = np.concatenate([np.zeros(RATE // 2), speak_tones("yego", RATE)])


def test_speech_from_an_alsa_device_through_portaudio_is_transcribed(tmp_path: Path) -> None:
    _virtual_microphone(tmp_path, [SPEECH])
    driver = _driver(tmp_path, "device speechfile\n")
    try:
        _read_until(driver.stdout, "/speechEvent/text: 'yego'")
    finally:
        stderr = _stop(driver)
    assert driver.returncode == 130
    assert (
        stderr.splitlines()[0]
        == "speech_event_driver: capturing 'speechfile' (device 0): 1 channel(s) at 48000 Hz"
    )


def test_two_channels_are_captured_and_mixed_down(tmp_path: Path) -> None:
    _virtual_microphone(tmp_path, [SPEECH, np.zeros_like(SPEECH)])  # speech on the left only
    driver = _driver(tmp_path, "device speech\nchannels 2\n")  # part of the name will do
    try:
        _read_until(driver.stdout, "/speechEvent/text: 'yego'")
    finally:
        stderr = _stop(driver)
    assert "2 channel(s) at 48000 Hz" in stderr.splitlines()[0]


def test_a_missing_device_is_said_once_with_the_devices_and_capture_starts_when_it_appears(
    tmp_path: Path,
) -> None:
    driver = _driver(tmp_path, "device speechfile\nretry_period 0.2\n")
    try:
        _read_until(
            driver.stderr,
            "speech_event_driver: no input device 'speechfile'; PortAudio finds no input device "
            "(is a microphone plugged in?); trying again every 0.2 s",
        )
        time.sleep(1.0)  # several tries: still one message
        _virtual_microphone(tmp_path, [SPEECH])  # plugged in
        _read_until(driver.stdout, "/speechEvent/text: 'yego'")
    finally:
        stderr = _stop(driver)
    assert stderr.splitlines()[:1] == [
        "speech_event_driver: capturing 'speechfile' (device 0): 1 channel(s) at 48000 Hz"
    ]  # the rest of stderr: after the missing-device line the reader thread took


class _CallbackAbort(Exception):
    """sounddevice.CallbackAbort: the callback ends its stream at once."""


class _FakeStream:
    """A stream that delivers ``blocks`` on a thread, then stops as an unplugged device does."""

    def __init__(self, blocks: List[np.ndarray], callback: Any) -> None:
        self._blocks, self._callback = blocks, callback
        self.active = True

    def start(self) -> None:
        def deliver() -> None:
            for block in self._blocks:
                try:
                    self._callback(block, block.shape[0], None, None)
                except _CallbackAbort:
                    break
            self.active = False

        threading.Thread(target=deliver, daemon=True).start()

    def abort(self) -> None:
        self.active = False

    def close(self) -> None:
        self.active = False


class _FakeSounddevice:
    """sounddevice as the Microphone uses it: one device at 44.1 kHz that comes and goes."""

    PortAudioError = RuntimeError
    CallbackAbort = _CallbackAbort

    def __init__(self, sessions: List[List[np.ndarray]]) -> None:
        self.sessions = sessions  # the blocks of each time the device is opened
        self.present = True
        self.default = type("Default", (), {"device": (0, 0)})()
        self.opened: List[Dict[str, Any]] = []

    def query_devices(self, index: Optional[int] = None) -> Any:
        device = {"index": 0, "name": "USB mic", "max_input_channels": 2, "default_samplerate": 44100.0}
        return device if index is not None else ([device] if self.present else [])

    def check_input_settings(self, **settings: Any) -> None:
        if settings["samplerate"] != 44100:
            raise self.PortAudioError("Invalid sample rate")

    def InputStream(self, callback: Any, **settings: Any) -> _FakeStream:
        self.opened.append(settings)
        return _FakeStream(self.sessions.pop(0) if self.sessions else [], callback)

    def _terminate(self) -> None:
        pass

    def _initialize(self) -> None:
        pass


def test_a_device_that_stops_mid_run_is_said_and_opened_again_and_audio_is_mixed_and_resampled() -> None:
    left = np.sin(2 * np.pi * 500 * np.arange(4410) / 44100).astype(np.float32)  # 50 whole periods
    block = np.stack([left, np.zeros_like(left)], axis=1)  # 0.1 s of stereo at 44.1 kHz
    audio_api = _FakeSounddevice([[block] * 10, [block] * 10])
    said: List[str] = []
    heard: List[np.ndarray] = []
    stop = threading.Event()
    config = DriverConfig(channels=2, retry_period=0.05)
    microphone = Microphone(config, heard.append, said.append, audio_api)
    runner = threading.Thread(target=microphone.run, args=(stop,))
    runner.start()
    deadline = time.monotonic() + 10
    while len(audio_api.opened) < 3 and time.monotonic() < deadline:
        time.sleep(0.01)
    stop.set()
    runner.join(10)
    assert said[:3] == [
        "capturing 'USB mic' (device 0): 2 channel(s) at 44100 Hz",
        "the input device 'USB mic' stopped; trying again every 0.05 s",
        "capturing 'USB mic' (device 0): 2 channel(s) at 44100 Hz",
    ]
    assert audio_api.opened[0] == {
        "device": 0,
        "channels": 2,
        "samplerate": 44100,
        "blocksize": 1024,
        "dtype": "float32",
    }
    captured = np.concatenate(heard)
    # 2 s at 44.1 kHz in two sessions, resampled to 48 kHz (less what each session's resampler
    # still holds: its filter delay, under 1000 samples), mixed down: half the left channel
    assert 2 * 48000 - 2 * 1000 <= captured.size < 2 * 48000
    assert float(np.max(captured)) == pytest.approx(0.5, abs=0.01)


def test_a_device_named_that_is_not_there_lists_the_devices_found() -> None:
    audio_api = _FakeSounddevice([])
    with pytest.raises(MicrophoneError) as error:
        find_device(audio_api, "webcam")
    assert str(error.value) == "no input device 'webcam'; input devices: 0 'USB mic' (2 ch)"
    assert find_device(audio_api, "0") == (0, "USB mic", 2)
    assert find_device(audio_api, "") == (0, "USB mic", 2)
