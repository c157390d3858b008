"""The presentation window (issue 9, item 3) on a real X server (Xvfb), with the real node on the
in-memory bus behind it; checked through its widgets and through a screenshot's pixels.

In the ros env: Debian's /usr/bin/python3 has Tk (python3-tk), and .ci/run installs xvfb and
imagemagick (its ``import`` takes the screenshot) with the ROS packages.
"""

import subprocess
import sys
import time
import tkinter as tk
from pathlib import Path
from typing import Dict, List

import numpy as np
import pytest

from fixtures.audio import speak_tones
from harness.cli import open_demo_window
from harness.processes import Processes
from harness.scenario import Say, Scenario
from speech_event import SIGNAL_TOPIC
from speech_event.adapters.executors import ClockExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.adapters.ros import RosTransport, call_service
from speech_event.config import SpeechEventConfig
from speech_event.gui import ERROR_COLOUR, TranscriptWindow, grammar_in, status_of
from speech_event.interfaces.services import SET_GRAMMAR_SERVICE
from speech_event.messages import (
    DiagnosticArray,
    DiagnosticStatus,
    Float32MultiArray,
    KeyValue,
    SetGrammarRequest,
    String,
)
from speech_event.node import SpeechEventNode
from speech_event.recognizers.tones import ToneRecognizer
from tests.helpers.application import APPLICATION
from tests.ros.conftest import wait_for

NOON = 12 * 3600.0


def _screenshot(display: str, path: Path) -> np.ndarray:
    """The whole screen as an RGB array (and a PNG at ``path`` for people to look at)."""
    subprocess.run(["import", "-display", display, "-window", "root", str(path)], check=True)
    ppm = subprocess.run(["convert", str(path), "ppm:-"], check=True, capture_output=True).stdout
    header = ppm.split(b"\n", 3)  # P6, "width height", 255, pixels
    width, height = (int(value) for value in header[1].split())
    return np.frombuffer(header[3], dtype=np.uint8)[: width * height * 3].reshape(height, width, 3)


def _colour(hex_colour: str) -> List[int]:
    return [int(hex_colour[i : i + 2], 16) for i in (1, 3, 5)]


def test_the_window_shows_texts_errors_in_red_the_newest_in_view_and_drives_the_node(
    display: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("TZ", "UTC")  # the window shows local time
    time.tzset()
    clock, bus = FakeClock(NOON), InMemoryBus()
    config = SpeechEventConfig(health_check_period=5.0)
    node = SpeechEventNode(
        config, bus, clock, ToneRecognizer(), ClockExecutor(clock), lambda language: ToneRecognizer()
    )
    sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    node.start()
    root = tk.Tk()
    root.geometry("+0+0")
    try:
        window = TranscriptWindow(root, bus, lambda name, _, request: bus.call(name, request), 28, clock.now)
        speech = speak_tones("yego", 48000)
        for start in range(0, speech.size, 4096):
            clock.advance(4096 / 48000)
            sound_detection.publish(Float32MultiArray(data=speech[start : start + 4096]))
        window.refresh()
        assert window.status.cget("text") == "hearing speech"
        clock.advance(2.0)
        for number in range(12):  # more than the window holds: the oldest scroll out of view
            bus.advertise("/speechEvent/text", String).publish(String(data=f"line {number}"))
        sound_detection.shutdown()
        clock.advance_to(NOON + 5.0)  # the health check: an error, and diagnostics that say so
        window.refresh()
        root.update()
        lines = window.lines()
        assert lines[0] == "12:00:01  yego"
        assert lines[-1] == "12:00:05  Error: soundDetection is down"
        assert window.history.tag_names("end-2l") == ("error",)
        assert window.status.cget("text") == "soundDetection down"
        assert window.history.dlineinfo("end-2l") is not None  # the newest line is in view
        assert window.history.dlineinfo("1.0") is None  # the oldest has scrolled away
        pixels = _screenshot(display, tmp_path / "speech_event_gui.png")
        red = np.all(pixels == _colour(ERROR_COLOUR), axis=2)
        assert red.sum() > 50  # the error's text, drawn in its colour
        # The presenter types a line; switches language; disables the node.
        window.entry.insert(0, "hello from the keyboard")
        window.publish_typed()
        window.language.set("kinyarwanda")
        window.switch_language()
        window.enabled.set(False)
        window.toggle_enabled()
        assert bus.call(SET_GRAMMAR_SERVICE, SetGrammarRequest("yes|no")).response == 1  # type: ignore[attr-defined]
        clock.advance_to(NOON + 10.0)
        window.refresh()
        assert window.lines()[-2:] == [
            "12:00:05  hello from the keyboard",
            "12:00:10  Error: soundDetection is down",
        ]
        assert (node.language, node.enabled) == ("kinyarwanda", False)
        assert window.status.cget("text") == "disabled · grammar: yes|no"
    finally:
        root.destroy()
        node.stop()


def test_on_ros_the_window_shows_the_nodes_texts_and_calls_its_services(
    display: str, roscore: Dict[str, str], tmp_path: Path
) -> None:
    config = tmp_path / "node.ini"
    config.write_text("health_check_period 1.0\n")  # no soundDetection: an error every second
    processes = Processes(roscore, tmp_path)
    root = tk.Tk()
    transport = RosTransport()
    try:
        processes.start("node", [sys.executable, str(APPLICATION), "-c", str(config), "--recognizer", "fake"])
        window = TranscriptWindow(root, transport, call_service)

        def shown() -> List[str]:
            window.refresh()
            return window.lines()

        wait_for(lambda: bool(shown()), "the node's first error in the window", 60)
        assert shown()[0].endswith("  Error: soundDetection is down")
        assert window.history.tag_names("1.0") == ("error",)
        window.language.set("kinyarwanda")
        window.switch_language()
        window.enabled.set(False)
        window.toggle_enabled()
        window.entry.insert(0, "typed on ros")
        window.publish_typed()
        wait_for(lambda: any(line.endswith("  typed on ros") for line in shown()), "the typed line back")
        # the services answered 1: the window shows no refusal
        assert [line for line in shown() if "refused" in line or "did not answer" in line] == []
    finally:
        transport.close()  # later tests count the publishers of /speechEvent/text
        root.destroy()
        processes.stop_all()


def test_the_demo_opens_the_window_on_its_in_memory_bus(display: str) -> None:
    scenario = Scenario(
        name="demo",
        source="demo",
        config=SpeechEventConfig(),
        steps=(Say("go to the kitchen"),),
        expected=("go to the kitchen",),
        voice="tones",
        recognizer="fake",
    )
    window = open_demo_window(scenario)
    try:
        window.root.update()
        (line,) = window.lines()
        assert line.endswith("  go to the kitchen")
        assert window.history.tag_names("1.0") == ("text",)
    finally:
        window.root.destroy()


def test_the_status_line_reads_the_nodes_diagnostics() -> None:
    def diagnostics(level: int, **values: str) -> DiagnosticArray:
        pairs = tuple(KeyValue(key.replace("_", " "), value) for key, value in values.items())
        return DiagnosticArray(0.0, (DiagnosticStatus(level, "speechEvent", "", "", pairs),))

    ok, warn, error = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR
    assert status_of(None) == "listening"
    assert status_of(diagnostics(ok, enabled="true", utterances_waiting_for_recognition="0")) == "listening"
    assert (
        status_of(diagnostics(ok, enabled="true", utterances_waiting_for_recognition="1")) == "transcribing"
    )
    assert status_of(diagnostics(warn, enabled="true")) == "transcribing"
    assert status_of(diagnostics(error, enabled="true")) == "soundDetection down"
    assert status_of(diagnostics(error, enabled="false")) == "disabled"
    assert grammar_in(None) is None
    assert grammar_in(diagnostics(ok, grammar="none (free speech)")) is None
    assert grammar_in(diagnostics(ok, grammar="yes|no")) == "yes|no"
