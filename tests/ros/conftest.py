"""Fixtures for the ros env. rospy is imported here unguarded: in this env a missing ROS is a
failure, never a skip (tests/ensure_debian_packages.sh installs it)."""

import os
import subprocess
from typing import Dict, Iterator, List

import pytest
import rospy

from fixtures.ros import ros_environment, wait_for
from harness.processes import Processes, free_port
from speech_event.adapters.ros import master_answers

# The scenario replays, run in parts, longest parts first (seconds a part on an AVX2 EPYC beside
# three other workers, 2026-12-07: 75-146, 68-98, 66-102, 33-63). pytest-xdist hands out the tests
# in the order collected, and in the order of the files the two hosts' parts came last: two of
# them ran on for a minute after the other workers had nothing left to take.
LONGEST_FIRST = (
    "test_every_tones_scenario_passes_with_the_node_on_another_host",
    "test_real_time_replay_passes_every_scenario_on_the_wall_clock",
    "test_every_scenario_passes_on_ros_with_the_in_memory_expectations",
    "test_every_tones_scenario_passes_on_ros_with_the_other_families_fixture_models",
)


def _rank(item: pytest.Item) -> int:
    name = getattr(item, "originalname", item.name)
    return LONGEST_FIRST.index(name) if name in LONGEST_FIRST else len(LONGEST_FIRST)


def pytest_collection_modifyitems(items: List[pytest.Item]) -> None:
    """Tests on the session's roscore share this process's rospy node, its topics and their
    connections: in another order they disturb each other (a typed line lost, a feedback missed,
    seen with pytest-xdist), so they all run in one worker, in the order of the files (pytest-xdist
    hands that group out first, as the unit of most tests). Every other test (the scenario
    replays, the two hosts) starts a roscore of its own and runs anywhere: the longest first."""
    for item in items:
        if "roscore" in getattr(item, "fixturenames", ()):
            item.add_marker(pytest.mark.xdist_group("this_process_rospy_node"))
    items.sort(key=_rank)  # stable: the files' order otherwise


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
