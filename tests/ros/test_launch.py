"""Both launch files under roslaunch, found through ROS_PACKAGE_PATH alone (no catkin build)."""

import os
import signal
import subprocess
import sys
import xml.etree.ElementTree as ElementTree
from pathlib import Path
from typing import List

import numpy as np
import rosgraph
import soundfile

from fixtures.audio import speak_tones
from fixtures.paths import ROOT
from fixtures.ros import ros_environment, serves, spoken, wait_for
from fixtures.text_listener import received, write_listener
from harness.processes import Processes, descendants, free_port
from speech_event import SIGNAL_TOPIC, TEXT_TOPIC

LAUNCH = ROOT / "launch"


def _roslaunch(port: int, launch_file: str, *arguments: str) -> List[str]:
    return ["roslaunch", "-p", str(port), "speech_event", launch_file, *arguments]


def test_the_robot_launch_brings_up_the_node_and_sigint_stops_it(tmp_path: Path) -> None:
    port = free_port()
    environment = ros_environment(port, tmp_path)
    processes = Processes(environment, tmp_path)
    launch = processes.start(
        "roslaunch", _roslaunch(port, "speech_event_launch_robot.launch", "recognizer:=fake")
    )
    try:
        master = rosgraph.Master("/launchTest", master_uri=environment["ROS_MASTER_URI"])

        def node_is_up() -> bool:
            try:
                publishers, subscribers, _ = master.getSystemState()
            except Exception:
                return False
            return [TEXT_TOPIC, ["/speechEvent"]] in publishers and [
                SIGNAL_TOPIC,
                ["/speechEvent"],
            ] in subscribers

        wait_for(node_is_up, "/speechEvent to subscribe and advertise", timeout=60)
        # What the Behaviour Controller and the action clients look for
        for service in ("/speechEvent/set_enabled", "/speechEvent/set_language"):
            wait_for(lambda service=service: serves(service, master.master_uri), service)
        action = "/speechEvent/recognise_speech_action"

        def action_and_diagnostics_are_up() -> bool:
            publishers, subscribers, _ = master.getSystemState()
            return (
                [f"{action}/result", ["/speechEvent"]] in publishers
                and [f"{action}/goal", ["/speechEvent"]] in subscribers
                and ["/diagnostics", ["/speechEvent"]] in publishers
            )

        wait_for(action_and_diagnostics_are_up, "the action's topics and /diagnostics")
        started = descendants(launch.pid)  # the master, rosout and the node
        assert len(started) >= 3
        os.killpg(launch.pid, signal.SIGINT)
        assert launch.wait(30) == 0
        wait_for(lambda: not any(Path(f"/proc/{pid}").exists() for pid in started), "all of it to stop", 30)
    finally:
        processes.stop_all()


def _test_harness_launch(tmp_path: Path, scenario: Path) -> str:
    port = free_port()
    environment = ros_environment(port, tmp_path)
    result = subprocess.run(
        _roslaunch(port, "speech_event_launch_test_harness.launch", f"scenario:={scenario}"),
        env=environment,
        capture_output=True,
        text=True,
        timeout=180,
    )
    return result.stdout


def test_the_test_harness_launch_passes_a_scenario_with_an_outage(tmp_path: Path) -> None:
    scenario = ROOT / "scenarios" / "outage_shutdown.toml"
    output = _test_harness_launch(tmp_path, scenario)
    assert (
        f"PASS  soundDetection shuts down cleanly after speech, then comes back  ({scenario}, 5 messages)"
        in output
    )


def test_the_test_harness_launch_reports_a_failure_with_its_diff(tmp_path: Path) -> None:
    scenario = tmp_path / "wrong.toml"
    scenario.write_text('name = "wrong"\n[[steps]]\nsay = "go left"\n[expect]\npublished = ["go right"]\n')
    output = _test_harness_launch(tmp_path, scenario)
    assert f"FAIL  wrong  ({scenario})" in output
    assert "      -go right\n      +go left\n" in output


def test_each_node_type_in_the_launch_files_is_exactly_one_executable_in_the_package_tree() -> None:
    types = {
        node.attrib["type"]
        for launch_file in LAUNCH.glob("*.launch")
        for node in ElementTree.parse(launch_file).getroot().iter("node")
    }
    assert types == {
        "speech_event_application.py",
        "speech_event_scenario_node.py",
        "sound_detection_replay.py",
        "speech_event_checker.py",
        "speech_event_driver.py",
        "speech_event_gui.py",
    }
    for name in types:
        found = [
            path
            for path in ROOT.rglob(name)
            if ".tox" not in path.parts and ".git" not in path.parts and os.access(path, os.X_OK)
        ]
        assert found == [ROOT / "scripts" / name], name


def test_the_driver_launch_runs_driver_node_and_window_with_one_command(display: str, tmp_path: Path) -> None:
    """As on a presenter's laptop (here a file stands in for the microphone): the driver publishes
    the file's speech, the node transcribes it, the window shows it."""
    rate = 48000
    session = np.concatenate([np.zeros(rate // 2), speak_tones("open the door", rate), np.zeros(rate // 2)])
    soundfile.write(str(tmp_path / "session.flac"), session, rate)
    port = free_port()
    environment = {**ros_environment(port, tmp_path), "DISPLAY": display}
    processes = Processes(environment, tmp_path)
    listener = processes.start("listener", [sys.executable, str(write_listener(tmp_path))])
    launch_arguments = [f"source:={tmp_path / 'session.flac'}", "recognizer:=fake", "gui:=true"]
    try:
        processes.start("roslaunch", _roslaunch(port, "speech_event_launch_driver.launch", *launch_arguments))
        master = rosgraph.Master("/launchTest", master_uri=environment["ROS_MASTER_URI"])
        wait_for(
            lambda: spoken([t for _, t in received(processes.log("listener"))]) == ["open the door"],
            "the text",
            90,
        )
        _, subscribers, _ = master.getSystemState()
        assert [TEXT_TOPIC, ["/listener", "/speechEventGui"]] in [[t, sorted(n)] for t, n in subscribers]
        assert listener.poll() is None
    finally:
        processes.stop_all()
