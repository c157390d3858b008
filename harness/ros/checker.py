"""The checker of the test-harness launch file: collects /speechEvent/text, with scenario times
(the stand-in drives /clock), while the autonomous soundDetection stand-in plays a scenario, then
prints the PASS/FAIL report and exits 0 or 1 (``required="true"`` ends the launch with it)."""

import argparse
import time
from typing import List, Optional

import rospy
from std_msgs.msg import String

from harness.outcome import Outcome, Published
from harness.processes import POLL_AT_MOST
from harness.report import passed, report
from harness.ros.connections import reaches_us
from harness.ros.stand_in import CHECKER_READY_TOPIC, CONNECT_TIMEOUT, DONE_TOPIC
from harness.scenario import add_scenario_arguments, scenario_from_arguments
from speech_event import TEXT_TOPIC
from speech_event.application import stop_on_ctrl_c, without_remappings


def main(argv: Optional[List[str]] = None) -> int:
    stop_on_ctrl_c()
    parser = argparse.ArgumentParser(prog="speech_event_checker")
    add_scenario_arguments(parser)
    arguments = parser.parse_args(without_remappings(argv))
    scenario = scenario_from_arguments(arguments)
    rospy.init_node("speechEventChecker", disable_signals=True)
    published: List[Published] = []
    rospy.Subscriber(TEXT_TOPIC, String, lambda m: published.append(Published(rospy.get_time(), m.data)))
    deadline = time.monotonic() + CONNECT_TIMEOUT
    while not reaches_us(TEXT_TOPIC) and time.monotonic() < deadline:
        time.sleep(POLL_AT_MOST)  # each poll asks the master and the node, as wait_until's do
    ready = rospy.Publisher(CHECKER_READY_TOPIC, String, queue_size=1, latch=True)
    ready.publish(String(data="listening"))
    rospy.wait_for_message(DONE_TOPIC, String)
    outcome = Outcome(published)
    print(report(scenario, outcome), flush=True)
    return 0 if passed(scenario, outcome) else 1
