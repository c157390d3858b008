"""harness/ros/connections.py: a subscription reaches us once its publisher has accepted it, not
when rospy counts it."""

import threading
from typing import Dict, List

import pytest
import rospy
import rospy.impl.tcpros_pubsub as tcpros_pubsub
from std_msgs.msg import String

from fixtures.ros import wait_for
from harness.ros.connections import reaches_us

TOPIC = "/test/reaches_us"


def test_a_counted_subscription_reaches_us_only_once_its_publisher_has_accepted_it(
    roscore: Dict[str, str], monkeypatch: pytest.MonkeyPatch
) -> None:
    held = threading.Event()
    connect = tcpros_pubsub.robust_connect_subscriber

    def when_released(*arguments: object) -> None:
        held.wait(30)
        connect(*arguments)

    monkeypatch.setattr(tcpros_pubsub, "robust_connect_subscriber", when_released)
    assert not reaches_us(TOPIC)  # nobody publishes it
    received: List[str] = []
    publisher = rospy.Publisher(TOPIC, String, queue_size=10)
    subscriber = rospy.Subscriber(TOPIC, String, lambda message: received.append(message.data))
    try:
        wait_for(lambda: subscriber.get_num_connections() == 1, "rospy to count the connection")
        assert not reaches_us(TOPIC)  # counted, not made: a message published now is lost
        publisher.publish(String(data="lost"))
        held.set()
        wait_for(lambda: reaches_us(TOPIC), "the publisher to accept the connection")
        publisher.publish(String(data="kept"))
        wait_for(lambda: received, "the message published once it reached us")
        assert received == ["kept"]
    finally:
        held.set()
        subscriber.unregister()
        publisher.unregister()
