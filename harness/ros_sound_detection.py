"""The soundDetection stand-in for replay on a real roscore (its own process).

It builds the scenario's timeline itself (the same, seeded, as the harness's) and publishes
events when told, one line each on stdin/stdout: it prints ``ready`` once the node is connected;
``publish I`` publishes event I and prints ``published I``; ``shutdown`` unregisters cleanly and
exits. The harness kills it with SIGKILL for a crash. With ``--wrong-type I`` it is instead another
node that publishes event I (a message of another type) on the topic once, then leaves.
"""

import argparse
import sys
import time
from typing import List, Optional

import rospy

from harness.scenario import load_scenario
from harness.timeline import Publish, build_timeline
from speech_event import SIGNAL_TOPIC
from speech_event.adapters.ros import RosTransport
from speech_event.config import SpeechEventConfig, load_config
from speech_event.messages import Float32MultiArray

CONNECT_TIMEOUT = 30.0


def _say(line: str) -> None:
    print(line, flush=True)


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(prog="sound_detection_replay")
    parser.add_argument("scenario")
    parser.add_argument("-c", "--config", help="configuration the scenario's [config] overrides")
    parser.add_argument("--wrong-type", type=int, metavar="I", help="publish event I as another node")
    arguments = parser.parse_args([word for word in (argv or sys.argv[1:]) if ":=" not in word])
    base = load_config(arguments.config) if arguments.config else SpeechEventConfig()
    events = build_timeline(load_scenario(arguments.scenario, base)).events
    transport = RosTransport()
    if arguments.wrong_type is not None:
        rospy.init_node("wrongTypePublisher", disable_signals=True)
        event = events[arguments.wrong_type]
        assert isinstance(event, Publish)
        intruder = transport.advertise(SIGNAL_TOPIC, type(event.message))
        intruder.publish(event.message)  # the node refuses the connection: nothing arrives
        intruder.unregister()
        return 0
    rospy.init_node("soundDetection", disable_signals=True)
    publisher = transport.advertise(SIGNAL_TOPIC, Float32MultiArray)
    deadline = time.monotonic() + CONNECT_TIMEOUT
    while publisher.connections() == 0:
        if time.monotonic() > deadline:
            _say(f"error: no subscriber connected to {SIGNAL_TOPIC} in {CONNECT_TIMEOUT:.0f} s")
            return 1
        time.sleep(0.005)
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
