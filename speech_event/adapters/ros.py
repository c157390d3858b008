"""The rospy adapters: RosTransport and RosClock. The only module of speech_event that imports rospy.

Audio arrives through rospy's numpy deserializer (np.frombuffer), so a 4096-float message costs
no per-float Python work. Publisher status combines the master's registrations with the
subscriber's live connections: a soundDetection killed with SIGKILL stays registered on the
master but its connection is gone, and that reads as down.
"""

import logging
import threading
from typing import Callable, Dict

import rosgraph
import rospy
from rospy.numpy_msg import numpy_msg
from std_msgs import msg as std_msgs

from speech_event import messages
from speech_event.ports import PublisherStatus

_LOG = logging.getLogger("speech_event")

# Bursts of blocks must not be dropped: soundDetection can flush a backlog after a stall.
AUDIO_QUEUE_SIZE = 1000
TEXT_QUEUE_SIZE = 100
# rospy's receive buffer: large enough for the biggest message the node accepts in one read.
AUDIO_BUFFER_BYTES = 1 << 24


def _to_ros(message: object) -> object:
    if isinstance(message, messages.String):
        return std_msgs.String(data=message.data)
    if isinstance(message, messages.Float32MultiArray):
        dims = [std_msgs.MultiArrayDimension(d.label, d.size, d.stride) for d in message.layout.dim]
        layout = std_msgs.MultiArrayLayout(dim=dims, data_offset=message.layout.data_offset)
        return std_msgs.Float32MultiArray(layout=layout, data=message.data)
    return message  # already a rospy message


_ROS_TYPES: Dict[type, type] = {
    messages.String: std_msgs.String,
    messages.Float32MultiArray: std_msgs.Float32MultiArray,
}


class RosPublisher:
    def __init__(self, publisher: rospy.Publisher) -> None:
        self._publisher = publisher

    def publish(self, message: object) -> None:
        self._publisher.publish(_to_ros(message))

    def unregister(self) -> None:
        self._publisher.unregister()

    def connections(self) -> int:
        return int(self._publisher.get_num_connections())


class RosTransport:
    def __init__(self) -> None:
        self._subscribers: Dict[str, rospy.Subscriber] = {}

    def advertise(self, topic: str, message_type: type) -> RosPublisher:
        ros_type = _ROS_TYPES.get(message_type, message_type)
        queue = AUDIO_QUEUE_SIZE if ros_type is std_msgs.Float32MultiArray else TEXT_QUEUE_SIZE
        return RosPublisher(rospy.Publisher(topic, ros_type, queue_size=queue))

    def subscribe(self, topic: str, message_type: type, callback: Callable[[object], None]) -> None:
        ros_type = _ROS_TYPES.get(message_type, message_type)
        if ros_type is std_msgs.Float32MultiArray:
            ros_type = numpy_msg(ros_type)
        self._subscribers[topic] = rospy.Subscriber(
            topic, ros_type, callback, queue_size=None, buff_size=AUDIO_BUFFER_BYTES, tcp_nodelay=True
        )

    def publisher_status(self, topic: str) -> PublisherStatus:
        try:
            publishers, _, _ = rosgraph.Master(rospy.get_name()).getSystemState()
        except Exception as problem:  # the master itself is gone: nothing can be confirmed
            _LOG.warning("cannot ask the ROS master about %s: %s", topic, problem)
            return PublisherStatus.NONE
        if not any(name == topic and nodes for name, nodes in publishers):
            return PublisherStatus.NONE
        subscriber = self._subscribers.get(topic)
        if subscriber is None or subscriber.get_num_connections() > 0:
            return PublisherStatus.CONNECTED
        return PublisherStatus.STALE


# Time arithmetic rounds to the nanosecond both ways, so a timer due exactly when /clock is
# stepped could miss that step by 1 ns. Timers fire this much early (within the node's
# TIMER_TOLERANCE, so the node takes them as due).
EARLY = 1e-4
# Longest single wait, so a cancelled timer's thread ends soon after.
_LONGEST_WAIT = 0.5


class RosTimer:
    """Runs a callback once ROS time reaches an absolute time.

    Not rospy.Timer: it counts its period from when its own thread starts, so a timer set for time
    T fired at T plus however late that thread started (seen in replay: a health check due at 2 s
    ran after an event at 2.024 s).
    """

    def __init__(self, when: float, callback: Callable[[], None]) -> None:
        self._cancelled = threading.Event()
        thread = threading.Thread(
            target=self._run, args=(when, callback), name="speech_event_timer", daemon=True
        )
        thread.start()

    def cancel(self) -> None:
        self._cancelled.set()

    def _run(self, when: float, callback: Callable[[], None]) -> None:
        while not self._cancelled.is_set():
            remaining = when - EARLY - rospy.get_time()
            if remaining <= 0:
                callback()
                return
            try:
                rospy.sleep(min(remaining, _LONGEST_WAIT))  # follows /clock under /use_sim_time
            except rospy.ROSInterruptException:  # the node is shutting down
                return


class RosClock:
    """ROS time: the wall clock, or /clock when /use_sim_time is set."""

    def now(self) -> float:
        return float(rospy.get_time())

    def call_at(self, when: float, callback: Callable[[], None]) -> RosTimer:
        return RosTimer(when, callback)


class RosLogHandler(logging.Handler):
    """Sends the node's log records to rosout, so they show in rqt_console and the launch log."""

    def emit(self, record: logging.LogRecord) -> None:
        text = self.format(record)
        if record.levelno >= logging.ERROR:
            rospy.logerr(text)
        elif record.levelno >= logging.WARNING:
            rospy.logwarn(text)
        elif record.levelno >= logging.INFO:
            rospy.loginfo(text)
        else:
            rospy.logdebug(text)


def start_ros_node(name: str, verbose: bool) -> None:
    """Register this process with the master and send the node's log records to rosout."""
    rospy.init_node(name)
    logger = logging.getLogger("speech_event")
    logger.addHandler(RosLogHandler())
    logger.setLevel(logging.INFO if verbose else logging.WARNING)
    logger.propagate = False  # rosout prints them already


def wait_for_shutdown() -> None:
    """Block until ROS shuts the node down (SIGINT, rosnode kill, the master going away)."""
    rospy.spin()
