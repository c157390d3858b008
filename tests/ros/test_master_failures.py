"""A ROS master that stops answering must not silence the node: its checks go on, on time.

The master is frozen with SIGSTOP, as when its host drops off the network: every question to it
hangs. Before the fix the health check logged through rospy's rosout handler (which asks the
master for a parameter on each call) and hung there: no error was published for 8 s, then 8 at
once. Topics are peer to peer, so a subscriber that is already connected must go on receiving.
"""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Dict

import rosgraph

from fixtures.application import APPLICATION
from fixtures.ros import ros_environment, serves, wait_for
from fixtures.text_listener import assert_errors_on_time, received, write_listener
from harness.processes import Processes, descendants, free_port
from speech_event.adapters.ros import master_answers

FREEZE_SECONDS = 8.0
PERIOD = 1.0


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
        processes.start("listener", [sys.executable, str(write_listener(tmp_path))])
        log = processes.log("listener")
        wait_for(lambda: len(received(log)) >= 2, "the listener to hear the node's errors", 60)
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
        assert_errors_on_time(received(log), frozen, thawed, PERIOD)
    finally:
        processes.stop_all()


def test_after_a_master_restart_the_node_registers_again_and_goes_on(tmp_path: Path) -> None:
    """roscore restarted on the same URI knows nothing of the running node; rospy does not register
    again by itself. The node's next check notices and registers its topics and services again."""
    port = free_port()
    environment: Dict[str, str] = ros_environment(port, tmp_path)
    uri = environment["ROS_MASTER_URI"]
    processes = Processes(environment, tmp_path)
    try:
        roscore = processes.start("roscore", ["roscore", "-p", str(port)])
        wait_for(lambda: master_answers(uri), "roscore")
        config = tmp_path / "node.ini"
        config.write_text(f"health_check_period {PERIOD}\n")
        processes.start("node", [sys.executable, str(APPLICATION), "-c", str(config), "--recognizer", "fake"])
        wait_for(lambda: serves("/speechEvent/set_language", uri), "the node's services", 60)
        processes.stop(roscore)
        assert not master_answers(uri)
        processes.start("roscore_again", ["roscore", "-p", str(port)])
        wait_for(lambda: master_answers(uri), "the new roscore")
        wait_for(lambda: serves("/speechEvent/set_language", uri), "set_language registered again", 30)
        publishers, subscribers, _ = rosgraph.Master("/probe", master_uri=uri).getSystemState()
        assert ["/speechEvent/text", ["/speechEvent"]] in publishers
        assert ["/soundDetection/signal", ["/speechEvent"]] in subscribers
        assert ["/speechEvent/recognise_speech_action/goal", ["/speechEvent"]] in subscribers
        # A newcomer finds the node through the new master: a listener hears its errors, and the
        # Behaviour Controller's service call is answered.
        processes.start("listener", [sys.executable, str(write_listener(tmp_path))])
        wait_for(lambda: len(received(processes.log("listener"))) >= 2, "the listener to hear the node", 60)
        call = subprocess.run(
            ["rosservice", "call", "/speechEvent/set_enabled", "status: 'true'"],
            env=environment,
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert call.stdout.strip() == "response: 1", call.stderr
    finally:
        processes.stop_all()
