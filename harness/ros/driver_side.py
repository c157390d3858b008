"""The driver's ROS side (harness/driver_node.py, ``--transport ros``, the default): this process
becomes the node soundDetection on the roscore, publishing on ROS time."""

import time
from typing import Any, Callable, Tuple

import rospy

from harness.link import Link
from speech_event import SIGNAL_TOPIC
from speech_event.adapters.ros import RosClock, RosTransport
from speech_event.messages import Float32MultiArray
from speech_event.ports import Clock

SUBSCRIBER_TIMEOUT = 30.0


def ros_side() -> Tuple[Link, Clock, Callable[[], bool]]:
    """soundDetection's link to the topic, the clock to play on, and whether ROS has shut down."""
    rospy.init_node("soundDetection")
    transport = RosTransport()

    def wait(publisher: Any) -> None:
        deadline = time.monotonic() + SUBSCRIBER_TIMEOUT
        while publisher.connections() == 0 and time.monotonic() < deadline and not rospy.is_shutdown():
            time.sleep(0.01)

    return (
        Link(lambda: transport.advertise(SIGNAL_TOPIC, Float32MultiArray), wait),
        RosClock(),
        rospy.is_shutdown,
    )
