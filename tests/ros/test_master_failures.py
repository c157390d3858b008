"""A ROS master that stops answering must not silence the node: its checks go on, on time.

The master is frozen with SIGSTOP, as when its host drops off the network: every question to it
hangs. Before the fix the health check logged through rospy's rosout handler (which asks the
master for a parameter on each call) and hung there: no error was published for 8 s, then 8 at
once. Topics are peer to peer, so a subscriber that is already connected must go on receiving.
"""

import os
import signal
import sys
import time
from pathlib import Path
from typing import Dict, List, Tuple

from harness.ros_runner import Processes, descendants, free_port
from speech_event import SOUND_DETECTION_DOWN
from tests.application import APPLICATION
from tests.ros.conftest import master_answers, ros_environment, wait_for

FREEZE_SECONDS = 8.0
PERIOD = 1.0

LISTENER = """
import sys, time
import rospy
from std_msgs.msg import String
rospy.init_node("listener", disable_signals=True)
rospy.Subscriber("/speechEvent/text", String, lambda m: print(f"{time.time():.3f} {m.data}", flush=True))
rospy.spin()
"""


def _received(log: Path) -> List[Tuple[float, str]]:
    lines = log.read_text().splitlines() if log.exists() else []
    return [(float(line.split(" ", 1)[0]), line.split(" ", 1)[1]) for line in lines if line[:1].isdigit()]


def test_a_frozen_master_does_not_delay_the_health_checks(tmp_path: Path) -> None:
    port = free_port()
    environment: Dict[str, str] = ros_environment(port, tmp_path)
    processes = Processes(environment, tmp_path)
    try:
        roscore = processes.start("roscore", ["roscore", "-p", str(port)])
        wait_for(lambda: master_answers(environment["ROS_MASTER_URI"]), "roscore")
        config = tmp_path / "node.ini"
        config.write_text(f"health_check_period {PERIOD}\n")  # no soundDetection: an error every check
        processes.start("node", [sys.executable, str(APPLICATION), "-c", str(config), "--recognizer", "fake"])
        (tmp_path / "listener.py").write_text(LISTENER)
        processes.start("listener", [sys.executable, str(tmp_path / "listener.py")])
        log = processes.log("listener")
        wait_for(lambda: len(_received(log)) >= 2, "the listener to hear the node's errors", 60)
        (master,) = [
            pid
            for pid in descendants(roscore.pid)
            if b"rosmaster" in Path(f"/proc/{pid}/cmdline").read_bytes()
        ]
        os.kill(master, signal.SIGSTOP)
        frozen = time.time()
        try:
            time.sleep(FREEZE_SECONDS)
        finally:
            os.kill(master, signal.SIGCONT)
        thawed = time.time()
        time.sleep(2.0)
        received = _received(log)
        during = [at for at, text in received if frozen < at <= thawed]
        assert all(text == SOUND_DETECTION_DOWN for _, text in received)
        # one error a second while the master is frozen, none held back for a burst afterwards
        assert len(during) >= FREEZE_SECONDS / PERIOD - 2, received
        assert (
            max(later - earlier for earlier, later in zip([frozen, *during], [*during, thawed])) < 2 * PERIOD
        )
        assert len([at for at, _ in received if thawed < at <= thawed + 0.5]) <= 1
    finally:
        processes.stop_all()
