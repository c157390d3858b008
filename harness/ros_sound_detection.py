"""The soundDetection stand-in for replay on a real roscore (its own process).

It builds the scenario's timeline itself (the same, seeded, as the harness's). Stepped by the
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
import subprocess
import sys
import time
from typing import List, Optional

import rospy
from rosgraph_msgs.msg import Clock
from std_msgs.msg import String

from harness.scenario import add_scenario_arguments, scenario_from_arguments
from harness.timeline import CallService, ComeUp, GoDown, Publish, SendGoal, Timeline, build_timeline
from speech_event import SIGNAL_TOPIC
from speech_event.adapters.ros import RosPublisher, RosTransport
from speech_event.application import without_remappings
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
        wrong_type_command = [sys.executable, "-m", "harness.ros_sound_detection", arguments.scenario]
        return _play_alone(timeline, publisher, [*wrong_type_command, *config_arguments, "--wrong-type"])
    return _play_stepped(events, publisher)
