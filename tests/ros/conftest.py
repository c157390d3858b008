"""Fixtures for the ros env. rospy is imported here unguarded: in this env a missing ROS is a
failure, never a skip (tests/ensure_debian_packages.sh installs it)."""

import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Dict, Iterator, List, Optional

import pytest
import rosgraph
import rospy

from fixtures.paths import ROOT
from harness.processes import Processes, free_port
from speech_event import SOUND_DETECTION_DOWN
from speech_event.adapters.ros import master_answers


def ros_environment(master_port: int, tmp_path: Path) -> Dict[str, str]:
    environment = dict(os.environ)
    environment.update(
        ROS_MASTER_URI=f"http://127.0.0.1:{master_port}",
        ROS_IP="127.0.0.1",
        ROS_HOME=str(tmp_path / "ros_home"),
        ROS_PACKAGE_PATH=str(ROOT),
        SPEECH_EVENT_PYTHON=sys.executable,
        PYTHONPATH=str(ROOT),
    )
    return environment


def spoken(texts: List[str]) -> List[str]:
    """The texts but soundDetection's outage reports: the node publishes one every health-check
    period while no driver publishes yet (or any longer), so how many depends on how fast the
    processes start on a loaded machine."""
    return [text for text in texts if text != SOUND_DETECTION_DOWN]


def wait_for(condition, what: str, timeout: float = 30.0, seen=None) -> None:  # type: ignore[no-untyped-def]
    """Poll ``condition``; on giving up, say what was awaited and, with ``seen``, what there was."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            found = f"; instead: {seen()}" if seen is not None else ""
            raise AssertionError(f"gave up after {timeout:.0f} s waiting for {what}{found}")
        time.sleep(0.01)


def serves(service: str, uri: Optional[str] = None) -> bool:
    """Whether the master (ROS_MASTER_URI's unless ``uri``) lists ``service``; no answer is no."""
    try:
        return bool(rosgraph.Master("/probe", master_uri=uri).lookupService(service))
    except Exception:
        return False


def pytest_collection_modifyitems(items: List[pytest.Item]) -> None:
    """Tests on the session's roscore share this process's rospy node, its topics and their
    connections: in another order they disturb each other (a typed line lost, a feedback missed,
    seen with pytest-xdist), so they all run in one worker, in the order of the files. Every
    other test (the scenario replays, the two hosts) starts a roscore of its own and runs anywhere."""
    for item in items:
        if "roscore" in getattr(item, "fixturenames", ()):
            item.add_marker(pytest.mark.xdist_group("this_process_rospy_node"))


@pytest.fixture(scope="session")
def roscore(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Dict[str, str]]:
    """A roscore of the test session's own on a free port; the test process is a ROS node on it."""
    port = free_port()
    work = tmp_path_factory.mktemp("roscore")
    environment = ros_environment(port, work)
    processes = Processes(environment, work)  # stops rosmaster and rosout too, whatever happens
    processes.start("roscore", ["roscore", "-p", str(port)])
    try:
        wait_for(lambda: master_answers(environment["ROS_MASTER_URI"]), "roscore")
        os.environ.update({k: environment[k] for k in ("ROS_MASTER_URI", "ROS_IP", "ROS_HOME")})
        rospy.init_node("speechEventTests", disable_signals=True)
        yield environment
    finally:
        rospy.signal_shutdown("tests done")
        processes.stop_all()


# One X server for the session: Tk keeps its connection to a display after its window is gone, and
# loses the whole process when that server stops.
@pytest.fixture(scope="session")
def display() -> Iterator[str]:
    # -displayfd: Xvfb takes the first free display and writes its number, so test processes side
    # by side (pytest-xdist workers) never race for one.
    read, write = os.pipe()
    server = subprocess.Popen(
        ["Xvfb", "-displayfd", str(write), "-screen", "0", "1024x768x24", "-nolisten", "tcp"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        pass_fds=(write,),
    )
    os.close(write)
    try:
        with os.fdopen(read) as announced:
            number = announced.readline().strip()
        assert number.isdigit() and server.poll() is None, "Xvfb did not start"
        old = os.environ.get("DISPLAY")
        os.environ["DISPLAY"] = f":{number}"
        yield f":{number}"
        if old is None:
            del os.environ["DISPLAY"]
        else:
            os.environ["DISPLAY"] = old
    finally:
        server.terminate()
        server.wait(10)
