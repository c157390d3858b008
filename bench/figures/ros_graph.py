"""A roscore of a benchmark's own, its publisher of soundDetection's blocks, and the node of this
tree started as its own process (bench/figures/ros.py, bench/figures/partial.py). Needs rospy."""

import contextlib
import os
import shutil
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Dict, Iterator

import rospy

from harness.processes import Processes, free_port, wait_until
from harness.ros.connections import reaches_us
from speech_event import SIGNAL_TOPIC
from speech_event.adapters.ros import RosTransport, master_answers
from speech_event.messages import Float32MultiArray

ROOT = Path(__file__).resolve().parents[2]
NODE_TIMEOUT = 60.0  # a node whose engine loads a large model takes a while to come up


@dataclass
class RosGraph:
    """The benchmark's side of the graph: it publishes as soundDetection and starts nodes."""

    work: Path
    environment: Dict[str, str]
    processes: Processes
    transport: RosTransport
    signal: Any  # the signal topic's publisher

    def start_node(self, settings: str, recognizer: str, subscribed: Callable[[], bool]) -> Any:
        """The node with these configuration lines; returns once it hears the signal and
        ``subscribed`` (the benchmark's subscriptions to its topics connected) holds."""
        config = self.work / "node.ini"
        config.write_text(settings)
        command = [sys.executable, "-m", "speech_event", "-c", str(config), "--recognizer", recognizer]
        node = self.processes.start("node", command)
        wait_until(
            lambda: self.signal.connections() > 0 and subscribed(), "the node to connect", NODE_TIMEOUT
        )
        return node

    def stop_node(self, node: Any) -> None:
        self.processes.stop(node)
        wait_until(lambda: self.signal.connections() == 0, "the node to disconnect")

    def subscribed(self, topic: str) -> Callable[[], bool]:
        """Whether our subscription to ``topic`` has a publisher connected (as it sees it)."""
        return lambda: reaches_us(topic)


@contextlib.contextmanager
def ros_graph(prefix: str) -> Iterator[RosGraph]:
    """A roscore on a free port of 127.0.0.1 and this process as the node soundDetection; every
    process started is stopped at the end, and its logs removed unless the run failed."""
    work = Path(tempfile.mkdtemp(prefix=prefix))
    port = free_port()
    environment = dict(
        os.environ,
        ROS_MASTER_URI=f"http://127.0.0.1:{port}",
        ROS_IP="127.0.0.1",
        ROS_HOME=str(work),
        PYTHONPATH=str(ROOT),  # the node of this tree, as the ROS replay starts it, not an installed copy
    )
    os.environ.update(environment)
    processes = Processes(environment, work)
    try:
        processes.start("roscore", ["roscore", "-p", str(port)])
        wait_until(lambda: master_answers(environment["ROS_MASTER_URI"]), "the benchmark's roscore")
        rospy.init_node("soundDetection", disable_signals=True)
        transport = RosTransport()
        signal = transport.advertise(SIGNAL_TOPIC, Float32MultiArray)
        yield RosGraph(work, environment, processes, transport, signal)
    except BaseException:
        print(f"the processes' logs are kept in {work}", file=sys.stderr)
        raise
    finally:
        rospy.signal_shutdown("bench done")
        processes.stop_all()
    shutil.rmtree(work, ignore_errors=True)  # a run that ended well: its logs are of no use
