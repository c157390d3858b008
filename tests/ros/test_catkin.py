"""catkin_make installs the package in a robot workspace."""

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

from fixtures.debian_packages import not_installed_by_the_project
from fixtures.paths import ROOT
from speech_event.msg import RecogniseSpeechAction
from speech_event.srv import SetEnabled, SetLanguage


def _configuration_files(cache: Path) -> "list[str]":
    """Every file in the folders where cmake found the packages it was asked for (``NAME_DIR``)."""
    found = re.findall(r"^\w+_DIR:PATH=(/usr/\S+)$", cache.read_text(), re.MULTILINE)
    return [str(path) for folder in sorted(set(found)) for path in sorted(Path(folder).glob("*.cmake"))]


def test_catkin_make_install_puts_the_nodes_launch_files_and_library_in_place(tmp_path: Path) -> None:
    source = tmp_path / "src" / "speech_event"
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(".git", ".tox", "*.egg-info", "__pycache__"))
    # The pyenv python3 first on PATH has no catkin_pkg: name the system Python, as on the robot.
    result = subprocess.run(
        ["catkin_make", "-C", str(tmp_path), "install", "-DPYTHON_EXECUTABLE=/usr/bin/python3"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    # what cmake read of Debian's ROS (catkin, message_generation, std_msgs, ...) is installed by
    # the project's own install step, not by hand
    configuration = _configuration_files(tmp_path / "build" / "CMakeCache.txt")
    assert len(configuration) > 10
    assert not_installed_by_the_project(configuration) == {}
    install = tmp_path / "install"
    for script in ("speech_event_application.py", "sound_detection_replay.py", "speech_event_checker.py"):
        installed = install / "lib" / "speech_event" / script
        assert installed.read_text().startswith("#!/usr/bin/python3\n"), script
    share = install / "share" / "speech_event"
    assert (share / "launch" / "speech_event_launch_robot.launch").is_file()
    # every program an installed launch file starts is installed with it
    launched = {
        found
        for launch in (share / "launch").glob("*.launch")
        for found in re.findall(r'pkg="speech_event" type="([^"]+)"', launch.read_text())
    }
    assert "speech_event_scenario_node.py" in launched
    assert sorted(p for p in launched if not (install / "lib" / "speech_event" / p).is_file()) == []
    assert (share / "config" / "speech_event_configuration.ini").is_file()
    library = install / "lib" / "python3" / "dist-packages"
    assert (library / "speech_event" / "node.py").is_file()
    assert (library / "speech_event" / "adapters" / "ros.py").is_file()
    # catkin built the robot interfaces from srv/ and action/: the same definitions (MD5) as the
    # project's own build step, which the ROS tests use.
    for module, built in (
        ("srv/_SetEnabled.py", SetEnabled),
        ("srv/_SetLanguage.py", SetLanguage),
        ("msg/_RecogniseSpeechAction.py", RecogniseSpeechAction),
    ):
        text = (library / "speech_event" / module).read_text()
        assert re.search(f"_md5sum = [\"']{built._md5sum}[\"']", text), module
    # Installed, the demo finds its command grammar (package data) from any folder.
    assert (library / "harness" / "data" / "robot_commands.txt").is_file()
    demo = subprocess.run(
        [sys.executable, "-m", "harness", "demo", "--voice", "tones", "--recognizer", "fake"],
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(library)},
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert demo.stdout.splitlines()[-1] == "/speechEvent/text at t=2.524 s: 'go to the kitchen'", demo.stderr
