"""A wheel, installed without -e, runs on ROS from any folder (issue 17, item 1): the interface
definitions ship in it, and their classes are built where the install can write them; its harness
replays a scenario on ROS without the checkout's scripts/ folder."""

import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path
from typing import Dict, Iterator, List

import pytest
import rospy

from fixtures.paths import ROOT
from fixtures.ros import serves, wait_for
from fixtures.wheel import build_wheel, install
from harness.processes import Processes
from speech_event.srv import SetLanguage


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return build_wheel(tmp_path_factory.mktemp("wheel"))


@pytest.fixture
def installed(wheel: Path, tmp_path: Path) -> Iterator[Path]:
    yield install(wheel, tmp_path / "site")


def _away_from_the_checkout(roscore: Dict[str, str], site: Path, tmp_path: Path) -> Dict[str, str]:
    """The ROS environment with only the installed copy importable (no checkout on the path)."""
    return {**roscore, "PYTHONPATH": str(site), "XDG_CACHE_HOME": str(tmp_path / "cache")}


def test_the_installed_console_script_serves_the_robot_from_another_folder(
    roscore: Dict[str, str], installed: Path, tmp_path: Path
) -> None:
    assert not (installed / "speech_event" / "srv").exists()
    assert (installed / "speech_event" / "definitions" / "srv" / "SetLanguage.srv").is_file()
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    processes = Processes(_away_from_the_checkout(roscore, installed, tmp_path), tmp_path)
    node = processes.start(
        "node", ["sh", "-c", f"cd {elsewhere} && exec {installed}/bin/speech-event --recognizer fake"]
    )
    try:
        wait_for(
            lambda: serves("/speechEvent/set_language"),
            "/speechEvent/set_language",
            seen=lambda: processes.last_lines("node"),
        )
        answer = rospy.ServiceProxy("/speechEvent/set_language", SetLanguage)(language="English")
        assert answer.response == 1
        # built beside the installed code, which this install can write
        assert (installed / "speech_event" / "srv" / "_SetLanguage.py").is_file()
        assert not (tmp_path / "cache").exists()
        os.killpg(node.pid, signal.SIGINT)
        assert node.wait(15) == 0
    finally:
        processes.stop_all()


def test_an_install_it_cannot_write_builds_its_classes_in_the_users_cache(
    installed: Path, tmp_path: Path
) -> None:
    code = (
        "from speech_event.adapters import ros_interfaces\n"
        "out = ros_interfaces.ensure_built(writable=False)\n"
        "from speech_event.srv import SetEnabled\n"
        "from speech_event.msg import RecogniseSpeechAction\n"
        "import speech_event.srv, speech_event.msg\n"
        "print(out)\n"
        "print(speech_event.srv.__file__)\n"
        "print(speech_event.msg.__file__)\n"
    )
    environment = {**os.environ, "PYTHONPATH": str(installed), "XDG_CACHE_HOME": str(tmp_path / "cache")}
    done = subprocess.run(
        [sys.executable, "-c", code],
        cwd=tmp_path,
        env=environment,
        capture_output=True,
        text=True,
        check=True,
    )
    out, srv, msg = done.stdout.splitlines()
    assert Path(out).parent == tmp_path / "cache" / "speech_event" / "ros_interfaces"
    assert (srv, msg) == (f"{out}/srv/__init__.py", f"{out}/msg/__init__.py")
    assert not (installed / "speech_event" / "srv").exists()


@pytest.mark.parametrize("timing", [[], ["--real-time"]], ids=["sim time", "real time"])
def test_the_installed_harness_replays_a_scenario_on_ros_from_another_folder(
    roscore: Dict[str, str], installed: Path, tmp_path: Path, timing: List[str]
) -> None:
    # It starts the node and the soundDetection stand-in as python -m modules of the install.
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    scenario = shutil.copy(ROOT / "scenarios" / "partials_fake.toml", elsewhere / "partials.toml")
    done = subprocess.run(
        [sys.executable, "-m", "harness", "run", "--transport", "ros", *timing, str(scenario)],
        cwd=elsewhere,
        env=_away_from_the_checkout(roscore, installed, tmp_path),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert (done.returncode, done.stdout.splitlines()[-1]) == (0, "1 passed, 0 failed"), (
        done.stdout + done.stderr
    )
