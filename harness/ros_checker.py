"""The checker of the test-harness launch file: collects /speechEvent/text, with scenario times
(the stand-in drives /clock), while the autonomous soundDetection stand-in plays a scenario, then
prints the PASS/FAIL report and exits 0 or 1 (``required="true"`` ends the launch with it)."""

import argparse
import sys
import time
from typing import List, Optional

import rospy
from std_msgs.msg import String

from harness.memory_runner import Published
from harness.report import passed, report
from harness.ros_sound_detection import CHECKER_READY_TOPIC, CONNECT_TIMEOUT, DONE_TOPIC
from harness.scenario import load_scenario
from speech_event import TEXT_TOPIC
from speech_event.config import SpeechEventConfig, load_config


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(prog="speech_event_checker")
    parser.add_argument("scenario")
    parser.add_argument("-c", "--config", help="configuration the scenario's [config] overrides")
    raw = sys.argv[1:] if argv is None else argv
    arguments = parser.parse_args([word for word in raw if ":=" not in word])
    base = load_config(arguments.config) if arguments.config else SpeechEventConfig()
    scenario = load_scenario(arguments.scenario, base)
    rospy.init_node("speechEventChecker", disable_signals=True)
    published: List[Published] = []
    texts = rospy.Subscriber(
        TEXT_TOPIC, String, lambda m: published.append(Published(rospy.get_time(), m.data))
    )
    deadline = time.monotonic() + CONNECT_TIMEOUT
    while texts.get_num_connections() == 0 and time.monotonic() < deadline:
        time.sleep(0.005)
    ready = rospy.Publisher(CHECKER_READY_TOPIC, String, queue_size=1, latch=True)
    ready.publish(String(data="listening"))
    rospy.wait_for_message(DONE_TOPIC, String)
    print(report(scenario, published), flush=True)
    return 0 if passed(scenario, published) else 1
