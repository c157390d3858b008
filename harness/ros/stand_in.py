"""The soundDetection stand-in of a replay on a real roscore: the process (``main``), and the
harness's side of it (``StandIns``).

The process builds the scenario's timeline itself (the same, seeded, as the harness's). Stepped by the
harness, it publishes events when told, one line each on stdin/stdout: it prints ``started`` once
it is a ROS node, not yet a publisher (so the harness can start the next incarnation during an
outage, and bring it up at once when the outage ends); ``advertise`` makes it a publisher, and it
prints ``ready`` once the node is connected; ``publish I`` publishes event I and prints
``published I``; ``shutdown`` unregisters cleanly and exits. The harness kills it with SIGKILL for
a crash. With ``--wrong-type I`` it is instead another node that publishes event I (a message of
another type) on the topic once.

With ``--autonomous`` (the test-harness launch file) it plays the whole timeline by itself, driving
/clock, once the checker listens, then says so on /speechEventReplay/done. A crash cannot be played
from inside the process that crashes, so there it refuses scenarios with ``kind = "crash"``.
"""

import argparse
import os
import signal
import subprocess
import sys
import time
from typing import Any, Callable, List, Optional

import rospy
from rosgraph_msgs.msg import Clock
from std_msgs.msg import String

from harness.processes import EVENT_TIMEOUT, Processes, ReplayError, wait_until
from harness.scenario import add_scenario_arguments, scenario_from_arguments
from harness.timeline import CallService, ComeUp, GoDown, Publish, SendGoal, Timeline, build_timeline
from speech_event import SIGNAL_TOPIC
from speech_event.adapters.ros import RosPublisher, RosTransport
from speech_event.application import stop_on_ctrl_c, without_remappings
from speech_event.messages import Float32MultiArray

CONNECT_TIMEOUT = 30.0
CLOCK_TICK = 0.005
CHECKER_READY_TOPIC = "/speechEventReplay/checker_ready"
DONE_TOPIC = "/speechEventReplay/done"


def _say(line: str) -> None:
    print(line, flush=True)


def _connected(publisher: RosPublisher) -> bool:
    deadline = time.monotonic() + CONNECT_TIMEOUT
    while publisher.connections() == 0:
        if time.monotonic() > deadline:
            _say(f"error: no subscriber connected to {SIGNAL_TOPIC} in {CONNECT_TIMEOUT:.0f} s")
            return False
        time.sleep(0.005)
    return True


def _publish_wrong_type(events: List[object], index: int) -> None:
    event = events[index]
    assert isinstance(event, Publish)
    rospy.init_node("wrongTypePublisher", disable_signals=True)
    intruder = RosTransport().advertise(SIGNAL_TOPIC, type(event.message))
    intruder.publish(event.message)  # the node refuses the connection: nothing arrives
    intruder.unregister()


def _play_stepped(events: List[object], publisher: RosPublisher) -> int:
    _say("ready")
    for line in sys.stdin:
        command, _, argument = line.strip().partition(" ")
        if command == "publish":
            event = events[int(argument)]
            assert isinstance(event, Publish)
            publisher.publish(event.message)
            _say("published " + argument)
        elif command == "shutdown":
            publisher.unregister()
            rospy.signal_shutdown("scenario: soundDetection shuts down")
            return 0
    return 0


def _play_alone(timeline: Timeline, publisher: RosPublisher, wrong_type_command: List[str]) -> int:
    # The launch file sets /use_sim_time and this process, which never dies in this mode, drives
    # /clock: the scenario's t = 0 is the node's start, as in the harness, and time runs at real pace.
    clock = rospy.Publisher("/clock", Clock, queue_size=10, latch=True)
    clock.publish(Clock(clock=rospy.Time(0)))
    rospy.wait_for_message(CHECKER_READY_TOPIC, String, timeout=CONNECT_TIMEOUT)
    events = list(enumerate(timeline.events))
    wall_start = time.monotonic()
    now = 0.0
    while now < timeline.end:
        time.sleep(CLOCK_TICK)
        now = min(time.monotonic() - wall_start, timeline.end)
        clock.publish(Clock(clock=rospy.Time.from_sec(now)))
        while events and events[0][1].time <= now:
            index, event = events.pop(0)
            if isinstance(event, Publish) and isinstance(event.message, Float32MultiArray):
                publisher.publish(event.message)
            elif isinstance(event, Publish):  # a node may not publish one topic with two types
                subprocess.run([*wrong_type_command, str(index)], check=True)
            elif isinstance(event, GoDown):
                publisher.unregister()
            elif isinstance(event, ComeUp):
                publisher = RosTransport().advertise(SIGNAL_TOPIC, Float32MultiArray)
                if not _connected(publisher):
                    return 1
    done = rospy.Publisher(DONE_TOPIC, String, queue_size=1, latch=True)
    done.publish(String(data="done"))
    rospy.spin()  # until the launch ends, so the latched messages stay available
    return 0


def main(argv: Optional[List[str]] = None) -> int:
    stop_on_ctrl_c()
    parser = argparse.ArgumentParser(prog="sound_detection_replay")
    add_scenario_arguments(parser)
    parser.add_argument("--wrong-type", type=int, metavar="I", help="publish event I as another node")
    parser.add_argument("--autonomous", action="store_true", help="play the timeline alone on ROS time")
    parser.add_argument("--name", default="soundDetection", help="the ROS node name of this incarnation")
    arguments = parser.parse_args(without_remappings(argv))
    timeline = build_timeline(scenario_from_arguments(arguments))
    events: List[object] = list(timeline.events)
    if arguments.wrong_type is not None:
        _publish_wrong_type(events, arguments.wrong_type)
        return 0
    if arguments.autonomous and any(isinstance(e, GoDown) and e.kind == "crash" for e in events):
        _say(f"error: {arguments.scenario} has a crash outage; replay it with python -m harness run")
        return 2
    if arguments.autonomous and any(isinstance(e, (CallService, SendGoal)) for e in events):
        _say(
            f"error: {arguments.scenario} calls services or sends action goals, which this stand-in "
            "does not check; replay it with python -m harness run --transport ros"
        )
        return 2
    rospy.init_node(arguments.name, disable_signals=not arguments.autonomous)
    if not arguments.autonomous:
        _say("started")
        if sys.stdin.readline().strip() != "advertise":
            return 0  # the replay ended before this incarnation came up
    publisher = RosTransport().advertise(SIGNAL_TOPIC, Float32MultiArray)
    if not _connected(publisher):
        return 1
    if arguments.autonomous:
        config_arguments = ["-c", arguments.config] if arguments.config else []
        wrong_type_command = [sys.executable, "-m", "harness.ros.stand_in", arguments.scenario]
        return _play_alone(timeline, publisher, [*wrong_type_command, *config_arguments, "--wrong-type"])
    return _play_stepped(events, publisher)


class StandIns:
    """The soundDetection processes of a replay: started, told to publish, shut down or killed.

    The next incarnation is started before it is needed, as a ROS node that is no publisher yet
    (under a name of its own, so a crashed one's stale registration stays for the node to find),
    and only advertises when the outage ends: a restart takes no scenario time, also in real time.
    In a scenario with an outage (``outages``) it starts with the first, beside the node under
    test, and again after each come-up, so that its start (Python and rospy: a second or more on
    a busy machine) falls in no outage: in real time the node's health checks wait for nobody,
    and outage_then_recovery's replay once heard a third error, from the check 0.46 s after
    soundDetection was due up (the CI's ros env beside three other replays; not reproduced).
    ``live_connections`` gives the node's live connections on the signal topic, as getBusStats
    does: [connection id, bytes received, messages received, drop estimate, connected].
    """

    def __init__(
        self,
        processes: Processes,
        scenario_path: str,
        base_config: Optional[str],
        live_connections: Callable[[], List[Any]],
        outages: bool = False,
    ) -> None:
        self._processes = processes
        # This module, as scripts/sound_detection_replay.py runs it; an installed harness has no scripts/.
        self._command = [sys.executable, "-m", "harness.ros.stand_in", scenario_path]
        if base_config:
            self._command += ["-c", base_config]
        self._live_connections = live_connections
        self._incarnations = 0
        # started now, heard from in come_up_first: it starts while the node under test does
        self._process = self._start()
        self._outages = outages
        # the next incarnation, started; it says "started" once it runs, read when it comes up
        self._next: Optional[subprocess.Popen[str]] = self._start() if outages else None
        self._sent = 0  # messages this incarnation has published
        self._intruders: List[subprocess.Popen[str]] = []  # the wrong-type publishers started

    def _start(self) -> "subprocess.Popen[str]":
        name = "soundDetection" if self._incarnations == 0 else f"soundDetection{self._incarnations}"
        self._incarnations += 1
        return self._processes.start("sound_detection", [*self._command, "--name", name], talk=True)

    def come_up_first(self) -> None:
        """The first incarnation, started with the others, advertises."""
        self._expect(self._process, "started")
        self._up(self._process)

    def _up(self, process: "subprocess.Popen[str]") -> "subprocess.Popen[str]":
        self._tell(process, "advertise")
        self._expect(process, "ready")
        return process

    @staticmethod
    def _expect(process: "subprocess.Popen[str]", expected: str) -> None:
        line = process.stdout.readline().strip() if process.stdout else ""
        if line != expected:
            raise ReplayError(f"the soundDetection stand-in said {line!r}, expected {expected!r}")

    @staticmethod
    def _tell(process: "subprocess.Popen[str]", command: str) -> None:
        assert process.stdin is not None
        process.stdin.write(command + "\n")
        process.stdin.flush()

    def publish(self, index: int, message: Float32MultiArray) -> None:
        """The incarnation that is up publishes event ``index`` (``message``: it builds the same
        timeline); back once the node has read it: it is stamped with the time it was read, and
        the node's timers wait for its callback (speech_event/adapters/ros.py, AudioInFlight)."""
        self._tell(self._process, f"publish {index}")
        self._expect(self._process, f"published {index}")
        self._sent += 1
        sent = self._sent
        wait_until(
            lambda: any(int(c[2]) >= sent for c in self._live_connections()),
            f"the node to receive message {sent}",
        )

    def intrude(self, index: int, message: object) -> None:
        """Another node publishes event ``index`` (a message of another type) on the topic.

        Not waited for here: starting a ROS node takes a second or more, which in real time would
        stop the scenario's next blocks for longer than a pause. Checked at the end."""
        self._intruders.append(
            self._processes.start("wrong_type", [*self._command, "--wrong-type", str(index)])
        )

    def go_down(self, crash: bool) -> None:
        """soundDetection shuts down, or is killed with SIGKILL; the next incarnation starts."""
        if crash:
            os.killpg(self._process.pid, signal.SIGKILL)
        else:
            self._tell(self._process, "shutdown")
        self._process.wait(EVENT_TIMEOUT)
        wait_until(lambda: not self._live_connections(), "the node to lose soundDetection")
        if self._next is None:
            self._next = self._start()

    def come_up(self) -> None:
        """The next incarnation advertises (started before, if it is not yet)."""
        process = self._next or self._start()
        self._expect(process, "started")
        self._process = self._up(process)
        self._next = self._start() if self._outages else None
        self._sent = 0

    def stop(self, *others: "subprocess.Popen[str]") -> None:
        """Every incarnation shut down, with ``others`` (the node) at the same time."""
        self._processes.stop(*[p for p in (self._process, self._next) if p is not None], *others)
        for intruder in self._intruders:
            if intruder.wait(EVENT_TIMEOUT) != 0:
                raise ReplayError("the wrong-type publisher failed; see its log")


if __name__ == "__main__":  # python -m harness.ros.stand_in, as the replay and --autonomous start it
    sys.exit(main())
