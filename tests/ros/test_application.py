"""The deployment node as a process: it comes up as speechEvent and stops cleanly on SIGINT."""

import os
import signal
import subprocess
import sys
import time
from typing import Dict

import rosgraph

from speech_event import SIGNAL_TOPIC
from speech_event.application import SHUTDOWN_GRACE_SECONDS
from tests.ros.conftest import ROOT, wait_for


def test_the_node_comes_up_as_speech_event_and_stops_on_sigint(roscore: Dict[str, str]) -> None:
    node = subprocess.Popen(
        [sys.executable, str(ROOT / "scripts" / "speech_event_application.py"), "--recognizer", "fake"],
        env=roscore,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    master = rosgraph.Master("/applicationTest")
    try:
        wait_for(
            lambda: [SIGNAL_TOPIC, ["/speechEvent"]] in master.getSystemState()[1],
            "/speechEvent to subscribe",
            60,
        )
        interrupted = time.monotonic()
        os.killpg(node.pid, signal.SIGINT)
        assert node.wait(SHUTDOWN_GRACE_SECONDS + 10) == 0
        assert time.monotonic() - interrupted < SHUTDOWN_GRACE_SECONDS + 10
        wait_for(lambda: [SIGNAL_TOPIC, ["/speechEvent"]] not in master.getSystemState()[1], "unsubscribed")
    finally:
        if node.poll() is None:
            os.killpg(node.pid, signal.SIGKILL)
            node.wait()
