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

from fixtures.application import APPLICATION
from fixtures.audio import speak_tones
from fixtures.ros import wait_for
from harness.cli import open_demo_window
from harness.processes import Processes
from harness.scenario import Say, Scenario
from speech_event import SIGNAL_TOPIC
from speech_event.adapters.executors import ClockExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.adapters.ros import RosPublisher, RosTransport, call_service
from speech_event.config import SpeechEventConfig
from speech_event.gui import (
    ERROR_COLOUR,
    PARTIAL_COLOUR,
    TEXT_COLOUR,
    TranscriptWindow,
    grammar_in,
    last_text_in,
    status_of,
)
from speech_event.interfaces.services import SET_GRAMMAR_SERVICE
from speech_event.messages import (
    NO_CONFIDENCE,
    DiagnosticArray,
    DiagnosticStatus,
    Float32MultiArray,
    KeyValue,
    SetGrammarRequest,
    String,
    TranscriptMessage,
)
from speech_event.node import SpeechEventNode
from speech_event.recognizers.tones import ToneRecognizer

NOON = 12 * 3600.0
# What python -m harness demo --gui plays.
DEMO = Scenario(
    name="demo",
    source="demo",
    config=SpeechEventConfig(),
    steps=(Say("go to the kitchen"),),
    expected=("go to the kitchen",),
    voice="tones",
    recognizer="fake",
)


def _screenshot(display: str, path: Path) -> np.ndarray:
    """The whole screen as an RGB array (and a PNG at ``path`` for people to look at)."""
    subprocess.run(["import", "-display", display, "-window", "root", str(path)], check=True)
    ppm = subprocess.run(["convert", str(path), "ppm:-"], check=True, capture_output=True).stdout
    header = ppm.split(b"\n", 3)  # P6, "width height", 255, pixels
    width, height = (int(value) for value in header[1].split())
    return np.frombuffer(header[3], dtype=np.uint8)[: width * height * 3].reshape(height, width, 3)


def _region(pixels: np.ndarray, widget: tk.Widget) -> np.ndarray:
    """The pixels of ``widget`` in a screenshot of the whole screen."""
    x, y = widget.winfo_rootx(), widget.winfo_rooty()
    return pixels[y : y + widget.winfo_height(), x : x + widget.winfo_width()]


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
        assert window.status.cget("text") == "soundDetection down · last text: english, no confidence"
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
        assert window.status.cget("text") == "disabled · grammar: yes|no · last text: english, no confidence"
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
        # rospy drops what is published before a subscriber connects: the window's own, here
        publisher = window.publisher
        assert isinstance(publisher, RosPublisher)
        wait_for(lambda: publisher.connections() > 0, "the window to hear its own topic")
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
    window = open_demo_window(DEMO)
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


def test_the_window_shows_the_text_so_far_dimmed_then_the_final_text_and_what_the_node_refused(
    display: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Issue 20: the partial text live, dimmed, on the line of the final text; the last text's
    language and confidence; the status at once after disabling; a refused language switch."""
    monkeypatch.setenv("TZ", "UTC")
    time.tzset()
    clock, bus = FakeClock(NOON), InMemoryBus()
    config = SpeechEventConfig(health_check_period=3600.0)  # partial_period: 0.5 s, the default
    # No engine for another language: set_language kinyarwanda is refused.
    node = SpeechEventNode(config, bus, clock, ToneRecognizer(), ClockExecutor(clock))
    sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    node.start()
    root = tk.Tk()
    root.geometry("+0+0")
    speech = speak_tones("go to the kitchen please", 48000)
    blocks = [speech[start : start + 4096] for start in range(0, speech.size, 4096)]

    def say(count: int) -> None:
        for block in blocks[:count]:
            clock.advance(4096 / 48000)
            sound_detection.publish(Float32MultiArray(data=block))
        del blocks[:count]
        window.refresh()
        root.update()

    try:
        window = TranscriptWindow(root, bus, lambda name, _, request: bus.call(name, request), 28, clock.now)
        say(7)  # the first block at 12:00:00.085, the first partial 0.5 s later
        assert window.lines() == ["12:00:00  go to th"]
        assert window.history.tag_names("end-2l") == ("partial",)
        pixels = _screenshot(display, tmp_path / "speech_event_gui_partial.png")
        assert np.all(pixels == _colour(PARTIAL_COLOUR), axis=2).sum() > 50  # drawn dimmed
        history = _region(pixels, window.history)
        assert not np.any(np.all(history == _colour(TEXT_COLOUR), axis=2))  # nothing final yet
        say(6)  # the next partial, 0.5 s after the first: it replaces it on the same line
        assert window.lines() == ["12:00:01  go to the kitchen"]
        say(len(blocks))
        clock.advance(2.0)  # the pause ends: the final text replaces the text so far
        window.refresh()
        root.update()
        assert window.lines() == ["12:00:02  go to the kitchen please"]
        assert window.history.tag_names("end-2l") == ("text",)
        assert window.status.cget("text") == "listening · last text: english, no confidence"
        window.language.set("kinyarwanda")
        window.switch_language()
        assert window.language.get() == "english"  # back on the language in force
        assert window.lines()[-1] == (
            "12:00:03  Error: the node refused to switch to kinyarwanda (/speechEvent/set_language answered 0)"
        )
        window.enabled.set(False)
        window.toggle_enabled()
        assert window.status.cget("text") == "disabled · last text: english, no confidence"  # at once
        clock.advance(20.0)
        window.entry.insert(0, "typed later")
        window.publish_typed()
        window.refresh()
        assert window.lines()[-1] == "12:00:23  typed later"
        root.update()
        _screenshot(display, tmp_path / "speech_event_gui_final.png")
    finally:
        root.destroy()
        node.stop()


def _seconds_of_day(stamp: str) -> int:
    parsed = time.strptime(stamp, "%H:%M:%S")
    return parsed.tm_hour * 3600 + parsed.tm_min * 60 + parsed.tm_sec


def test_lines_typed_after_the_demo_ran_carry_the_time_they_were_typed(display: str) -> None:
    wall = [1000.0]
    window = open_demo_window(DEMO, wall=lambda: wall[0])
    try:
        for typed_at, line in ((1010.0, "first"), (1030.0, "second")):
            wall[0] = typed_at
            window.entry.insert(0, line)
            window.publish_typed()
            window.refresh()
        seconds = [_seconds_of_day(line.split("  ")[0]) for line in window.lines()]
        # The demo's text in its own time; then the wall clock, on from where the demo ended.
        assert seconds[2] - seconds[1] == 20
        assert 10 <= seconds[1] - seconds[0] <= 12
    finally:
        window.root.destroy()


def test_the_status_line_gives_the_last_texts_language_and_confidence() -> None:
    def final(confidence: float) -> TranscriptMessage:
        return TranscriptMessage(1.0, "yego", True, confidence, "kinyarwanda", "NemoRecognizer", 0.1, 0.5)

    assert last_text_in(None) is None
    assert last_text_in(final(0.871)) == "kinyarwanda, confidence 0.87"
    assert last_text_in(final(NO_CONFIDENCE)) == "kinyarwanda, no confidence"
