"""The rospy adapters: RosTransport and RosClock. The only module of speech_event that imports rospy.

Audio arrives through rospy's numpy deserializer (np.frombuffer), so a 4096-float message costs
no per-float Python work. Publisher status combines the master's registrations with the
subscriber's live connections: a soundDetection killed with SIGKILL stays registered on the
master but its connection is gone, and that reads as down. Services are rospy services and the
action an actionlib ActionServer, over the classes genpy builds from srv/ and action/
(speech_event/adapters/ros_interfaces.py); requests, goals and results cross as the plain
dataclasses of speech_event.messages, field by field.
"""

import contextlib
import dataclasses
import http.client
import importlib
import logging
import logging.handlers
import os
import queue
import signal
import threading
import time
import xmlrpc.client
from typing import Any, Callable, Dict, Iterator, List, Optional, Tuple

import actionlib
import rosgraph
import rospy
from diagnostic_msgs import msg as diagnostic_msgs
from rospy.numpy_msg import numpy_msg
from std_msgs import msg as std_msgs

from speech_event import messages
from speech_event.adapters import ros_interfaces
from speech_event.ports import ActionGoal, PublisherStatus

ros_interfaces.ensure_built()

_LOG = logging.getLogger("speech_event")

# Bursts of blocks must not be dropped: soundDetection can flush a backlog after a stall.
AUDIO_QUEUE_SIZE = 1000
TEXT_QUEUE_SIZE = 100
# rospy's receive buffer: large enough for the biggest message the node accepts in one read.
AUDIO_BUFFER_BYTES = 1 << 24


class AudioInFlight:
    """The audio messages read off their connection whose callback has not finished yet.

    rospy reads a message, counts it in its bus statistics, then calls back on the same thread,
    where the node may wait for its lock. A sim-time replay moves /clock on once the node has
    received a block (harness/ros/runner.py), which is that count: the callback could then run
    after the next clock step, and a timer due by then (a pause ending, a speculation gap) could
    act before the block it should have seen. So a block is stamped with the ROS time when it is
    read, before the count (``ReceivedAudio``), and a timer due after a block still in flight waits
    for its callback (``RosTimer``). One per process, as rospy's connections are."""

    def __init__(self) -> None:
        self._changed = threading.Condition()
        self._stamps: Dict[int, float] = {}  # by message identity: when each was read

    def read(self, message: object) -> float:
        """``message`` was read off its connection now; its ROS time is returned."""
        stamp = float(rospy.get_time())
        with self._changed:
            self._stamps[id(message)] = stamp
        return stamp

    def taken(self, message: object) -> None:
        """The callback of ``message`` has finished."""
        with self._changed:
            if self._stamps.pop(id(message), None) is not None:
                self._changed.notify_all()

    def wait_for_those_read_by(self, when: float, timeout: float) -> bool:
        """Wait until no message read at or before ``when`` is still in flight; False when
        ``timeout`` ran out first."""
        with self._changed:
            return self._changed.wait_for(
                lambda: all(stamp > when for stamp in self._stamps.values()), timeout
            )


AUDIO_IN_FLIGHT = AudioInFlight()


class ReceivedAudio(numpy_msg(std_msgs.Float32MultiArray)):  # type: ignore[misc]
    """soundDetection's message, numpy-deserialized, with ``received_at``: the ROS time it was
    read off its connection (AudioInFlight says why that and not when its callback runs).

    No ``__slots__`` here: genpy's message functions (str, ==) walk the fields named by the class's
    ``__slots__``, which stay the message's own."""

    received_at: float

    def deserialize(self, data: bytes) -> "ReceivedAudio":
        super().deserialize(data)
        self.received_at = AUDIO_IN_FLIGHT.read(self)
        return self


def _to_ros(message: object) -> object:
    if isinstance(message, messages.String):
        return std_msgs.String(data=message.data)
    if isinstance(message, messages.DiagnosticArray):
        statuses = [
            diagnostic_msgs.DiagnosticStatus(
                level=status.level,
                name=status.name,
                message=status.message,
                hardware_id=status.hardware_id,
                values=[diagnostic_msgs.KeyValue(key=v.key, value=v.value) for v in status.values],
            )
            for status in message.status
        ]
        header = std_msgs.Header(stamp=rospy.Time.from_sec(message.stamp))
        return diagnostic_msgs.DiagnosticArray(header=header, status=statuses)
    if isinstance(message, messages.TranscriptMessage):
        return generated_class(message._type, "msg")(
            header=std_msgs.Header(stamp=rospy.Time.from_sec(message.stamp)),
            text=message.text,
            final=message.final,
            confidence=message.confidence,
            language=message.language,
            engine=message.engine,
            first_block=rospy.Time.from_sec(message.first_block),
            last_block=rospy.Time.from_sec(message.last_block),
        )
    if isinstance(message, messages.Float32MultiArray):
        dims = [std_msgs.MultiArrayDimension(d.label, d.size, d.stride) for d in message.layout.dim]
        layout = std_msgs.MultiArrayLayout(dim=dims, data_offset=message.layout.data_offset)
        return std_msgs.Float32MultiArray(layout=layout, data=message.data)
    return message  # already a rospy message


def generated_class(type_name: str, kind: str) -> Any:
    """The genpy class of ``package/Name`` in the package's ``msg`` or ``srv`` module."""
    package, name = type_name.split("/")
    return getattr(importlib.import_module(f"{package}.{kind}"), name)


_ROS_TYPES: Dict[type, type] = {
    messages.String: std_msgs.String,
    messages.Float32MultiArray: std_msgs.Float32MultiArray,
    messages.DiagnosticArray: diagnostic_msgs.DiagnosticArray,
    messages.TranscriptMessage: generated_class(messages.TranscriptMessage._type, "msg"),
}


def transcript_from_ros(message: Any) -> messages.TranscriptMessage:
    """A speech_event/Transcript as it came off ROS, as the plain message (_to_ros's inverse)."""
    return messages.TranscriptMessage(
        stamp=message.header.stamp.to_sec(),
        text=message.text,
        final=message.final,
        confidence=message.confidence,
        language=message.language,
        engine=message.engine,
        first_block=message.first_block.to_sec(),
        last_block=message.last_block.to_sec(),
    )


def _from_ros(ours: type, message: object) -> Any:
    return ours(**{field.name: getattr(message, field.name) for field in dataclasses.fields(ours)})


def _as_ros(ros_type: Any, message: Any) -> Any:
    return ros_type(**dataclasses.asdict(message))


class RosActionGoal:
    """The ActionGoal port over actionlib's ServerGoalHandle."""

    def __init__(self, handle: Any, action: messages.ActionType, forget: Callable[[str], None]) -> None:
        self._handle = handle
        self._action = action
        self._forget = forget
        self.goal_id = str(handle.get_goal_id().id)
        self._goal = _from_ros(action.goal, handle.get_goal())

    @property
    def goal(self) -> object:
        return self._goal

    def accept(self) -> None:
        self._handle.set_accepted()

    def feedback(self, feedback: object) -> None:
        self._handle.publish_feedback(
            _as_ros(generated_class(self._action.name + "Feedback", "msg"), feedback)
        )

    def succeed(self, result: object) -> None:
        self._handle.set_succeeded(self._result(result))
        self._forget(self.goal_id)

    def abort(self, result: object) -> None:
        self._handle.set_aborted(self._result(result))
        self._forget(self.goal_id)

    def cancel(self, result: object) -> None:
        self._handle.set_canceled(self._result(result))
        self._forget(self.goal_id)

    def _result(self, result: object) -> Any:
        return _as_ros(generated_class(self._action.name + "Result", "msg"), result)


class RosPublisher:
    """A rospy.Publisher that takes the messages of speech_event.messages as well as rospy's."""

    def __init__(self, publisher: rospy.Publisher) -> None:
        self._publisher = publisher

    def publish(self, message: object) -> None:
        self._publisher.publish(_to_ros(message))

    def unregister(self) -> None:
        self._publisher.unregister()

    def connections(self) -> int:
        return int(self._publisher.get_num_connections())


class _TimeoutTransport(xmlrpc.client.Transport):
    def __init__(self, timeout: float) -> None:
        super().__init__()
        self._timeout = timeout

    def make_connection(self, host: Any) -> http.client.HTTPConnection:
        connection = super().make_connection(host)
        connection.timeout = self._timeout
        return connection


# A master query takes far less than this on a working network; the node's checks use less.
MASTER_TIMEOUT = 1.0


class RosTransport:
    """The Transport port on rospy: topics, services, and actions through actionlib."""

    def __init__(self, master_timeout: float = MASTER_TIMEOUT) -> None:
        """``master_timeout``: the longest a question to the ROS master may take (keep it under the
        health check period, so every check ends in time)."""
        self._timeout = master_timeout
        self._subscribers: Dict[str, rospy.Subscriber] = {}
        self._publishers: List[RosPublisher] = []
        self._services: Dict[str, rospy.Service] = {}
        self._action_servers: Dict[str, actionlib.ActionServer] = {}
        # Goals by id: actionlib hands the cancel callback a new handle object for the same goal.
        self._goals: Dict[str, RosActionGoal] = {}
        self._goals_lock = threading.Lock()
        self._registering: Optional[threading.Thread] = None

    def advertise(self, topic: str, message_type: type) -> RosPublisher:
        ros_type = _ROS_TYPES.get(message_type, message_type)
        queue = AUDIO_QUEUE_SIZE if ros_type is std_msgs.Float32MultiArray else TEXT_QUEUE_SIZE
        publisher = RosPublisher(rospy.Publisher(topic, ros_type, queue_size=queue))
        self._publishers.append(publisher)
        return publisher

    def close(self) -> None:
        """Unregister the topics this transport advertised and subscribed to (a window closed in a
        process that goes on; a node's process unregisters everything as it ends anyway)."""
        for publisher in self._publishers:
            publisher.unregister()
        for subscriber in self._subscribers.values():
            subscriber.unregister()
        self._publishers, self._subscribers = [], {}

    def subscribe(self, topic: str, message_type: type, callback: Callable[[object], None]) -> None:
        ros_type = _ROS_TYPES.get(message_type, message_type)
        if ros_type is std_msgs.Float32MultiArray:
            ros_type, callback = ReceivedAudio, _in_flight_until_taken(callback)
        self._subscribers[topic] = rospy.Subscriber(
            topic, ros_type, callback, queue_size=None, buff_size=AUDIO_BUFFER_BYTES, tcp_nodelay=True
        )

    def publisher_status(self, topic: str) -> PublisherStatus:
        subscriber = self._subscribers.get(topic)
        live = subscriber is None or subscriber.get_num_connections() > 0
        try:
            publishers, subscribers = self._master_lists(topic)
        except (OSError, xmlrpc.client.Error) as problem:  # timed out, refused, gone: no wait
            _LOG.debug("the ROS master did not answer about %s: %s", topic, problem)
            return PublisherStatus.CONNECTED_MASTER_SILENT if live else PublisherStatus.NONE_MASTER_SILENT
        if subscriber is not None and rospy.get_name() not in subscribers:
            self._register_again()  # a new master (restarted) that does not know this node
        if not publishers:
            return PublisherStatus.NONE
        return PublisherStatus.CONNECTED if live else PublisherStatus.STALE

    def _master_lists(self, topic: str) -> Tuple[List[str], List[str]]:
        """The publishers and subscribers the master lists for ``topic``, asked with a timeout: a
        master that does not answer (its host unreachable, the process stopped) must not hold up
        a check."""
        master = xmlrpc.client.ServerProxy(
            rosgraph.get_master_uri(), transport=_TimeoutTransport(self._timeout)
        )
        answer: Any = master.getSystemState(rospy.get_name())
        code, message, state = answer
        if code != 1:
            raise xmlrpc.client.Fault(int(code), str(message))

        def nodes(listing: List[Any]) -> List[str]:
            return [node for name, names in listing if name == topic for node in names]

        return nodes(state[0]), nodes(state[1])

    def _register_again(self) -> None:
        """Register every publication, subscription and service of this process with the master
        again, on a thread of its own (rospy retries until the master takes them). rospy does not
        do it by itself when roscore is restarted. Not while shutting down: rospy has unregistered
        everything then, and the master rightly does not know this node any more."""
        if rospy.core.is_shutdown_requested():
            return
        with self._goals_lock:
            if self._registering is not None and self._registering.is_alive():
                return
            self._registering = threading.Thread(target=_register_everything, name="speech_event_register")
            self._registering.start()

    def serve(self, name: str, service: messages.ServiceType, handler: Callable[[object], object]) -> None:
        ros_service = generated_class(service.name, "srv")

        def answer(request: object) -> object:
            return _as_ros(ros_service._response_class, handler(_from_ros(service.request, request)))

        self._services[name] = rospy.Service(name, ros_service, answer)

    def serve_action(
        self,
        name: str,
        action: messages.ActionType,
        on_goal: Callable[[ActionGoal], None],
        on_cancel: Callable[[ActionGoal], None],
    ) -> None:
        # actionlib calls back holding its server lock, which a goal handle's __del__ also takes
        # (whenever the garbage collector runs it, on any thread, maybe one holding the node's
        # lock). So the node's code never runs under that lock: the callbacks only hand the goal
        # to a thread of this action's own, in arrival order.
        calls: queue.Queue[Callable[[], None]] = queue.Queue()  # novermin

        def goal_arrived(handle: Any) -> None:
            goal = RosActionGoal(handle, action, self._forget_goal)
            with self._goals_lock:
                self._goals[goal.goal_id] = goal
            calls.put(lambda: on_goal(goal))

        def cancel_arrived(handle: Any) -> None:
            with self._goals_lock:
                goal = self._goals.get(str(handle.get_goal_id().id))
            if goal is not None:
                calls.put(lambda: on_cancel(goal))

        def serve() -> None:
            while True:
                call = calls.get()
                try:
                    call()
                except Exception:  # one bad goal must not end the action
                    _LOG.exception("%s: handling a goal failed", name)

        threading.Thread(target=serve, name="speech_event_action", daemon=True).start()
        server = actionlib.ActionServer(
            name,
            generated_class(action.name + "Action", "msg"),
            goal_arrived,
            cancel_arrived,
            auto_start=False,
        )
        server.start()
        self._action_servers[name] = server

    def _forget_goal(self, goal_id: str) -> None:
        with self._goals_lock:
            self._goals.pop(goal_id, None)


# Time arithmetic rounds to the nanosecond both ways, so a timer due exactly when /clock is
# stepped could miss that step by 1 ns. Timers fire this much early (within the node's
# TIMER_TOLERANCE (speech_event/ports.py), so the node takes them as due).
EARLY = 1e-4
# Longest single wait, so a cancelled timer's thread ends soon after.
_LONGEST_WAIT = 0.5


def _in_flight_until_taken(callback: Callable[[object], None]) -> Callable[[object], None]:
    def take(message: object) -> None:
        try:
            callback(message)
        finally:
            AUDIO_IN_FLIGHT.taken(message)

    return take


class RosTimer:
    """Runs a callback once ROS time reaches an absolute time.

    Not rospy.Timer: it counts its period from when its own thread starts, so a timer set for time
    T fired at T plus however late that thread started (seen in replay: a health check due at 2 s
    ran after an event at 2.024 s). Nor rospy.sleep: under /use_sim_time it takes a clock at 0 for
    no clock yet and counts its whole duration from the first time after it, so a timer set at 0
    for 1 s, the clock stepped from 0 to 1, waited for 1.5 (a health check of a replay whose
    soundDetection was down from the start). It waits on rospy's time condition, which /clock
    notifies (on the wall clock nothing does: the wait is a sleep), and reads the time again.
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
        ticks = rospy.rostime.get_rostime_cond()
        while not self._cancelled.is_set() and not rospy.is_shutdown():
            with ticks:  # read under the lock /clock notifies under: no step is missed
                remaining = when - EARLY - rospy.get_time()
                if remaining > 0:
                    ticks.wait(min(remaining, _LONGEST_WAIT))
            if remaining <= 0:
                # A block read by now is the node's before the timer is (AudioInFlight).
                while not AUDIO_IN_FLIGHT.wait_for_those_read_by(when, _LONGEST_WAIT):
                    if self._cancelled.is_set() or rospy.is_shutdown():
                        return
                if not self._cancelled.is_set():
                    callback()
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


SERVICE_TIMEOUT = 5.0


def call_service(name: str, service: messages.ServiceType, request: object) -> object:
    """Call a service of ours by name (the GUI's language switch and enable toggle): our request
    dataclass in, our response dataclass out; rospy's exception when nobody serves it in time."""
    ros_service = generated_class(service.name, "srv")
    rospy.wait_for_service(name, timeout=SERVICE_TIMEOUT)
    answer = rospy.ServiceProxy(name, ros_service)(_as_ros(ros_service._request_class, request))
    return _from_ros(service.response, answer)


def master_answers(uri: Optional[str] = None, timeout: float = MASTER_TIMEOUT) -> bool:
    """Whether the ROS master at ``uri`` (default ROS_MASTER_URI's) answers within ``timeout``."""
    master = xmlrpc.client.ServerProxy(uri or rosgraph.get_master_uri(), transport=_TimeoutTransport(timeout))
    try:
        master.getPid("/speechEvent")
    except (OSError, xmlrpc.client.Error):
        return False
    return True


def wait_for_master(say: Callable[[str], None], poll_seconds: float = 0.5) -> None:
    """Return once the master answers, having said once (through ``say``) that the node waits for it.

    rospy.init_node would wait too, but silently behind a repeated "Unable to register with
    master", and a Ctrl-C there ends in a traceback; here it is a KeyboardInterrupt the caller
    ends cleanly."""
    if master_answers():
        return
    say(f"waiting for the ROS master at {rosgraph.get_master_uri()} (ROS_MASTER_URI); Ctrl-C stops")
    while not master_answers():
        time.sleep(poll_seconds)


def start_ros_node(name: str, verbose: bool) -> None:
    """Register this process with the master and send the node's log records to rosout.

    The records go through a queue to a thread of their own: rospy's rosout handler asks the master
    for a parameter on every call, and with the master's host unreachable that call hangs, so a
    log call on a timer thread would hold up the health checks (and every thread waiting for the
    logging lock behind it)."""
    rospy.init_node(name)
    records: queue.Queue[logging.LogRecord] = queue.Queue()  # novermin
    # Its thread is a daemon and is never joined: rospy runs shutdown hooks in the SIGINT handler,
    # on a main thread that may hold a logging lock the listener waits for.
    logging.handlers.QueueListener(records, RosLogHandler()).start()
    logger = logging.getLogger("speech_event")
    logger.addHandler(logging.handlers.QueueHandler(records))
    logger.setLevel(logging.INFO if verbose else logging.WARNING)
    logger.propagate = False  # rosout prints them already


def start_anonymous_node(name: str) -> None:
    """Register this process with the master as ``name`` with a unique suffix (several windows may
    run at once)."""
    rospy.init_node(name, anonymous=True)


def _register_everything() -> None:
    from rospy.impl.registration import (
        Registration,
        get_registration_listeners,
        get_service_manager,
        get_topic_manager,
    )

    _LOG.warning(
        "the ROS master does not know this node (restarted?): registering its topics and services again"
    )
    listeners = get_registration_listeners()
    topics = get_topic_manager()
    for name, kind in topics.get_publications():
        listeners.notify_added(name, kind, Registration.PUB)
    for name, kind in topics.get_subscriptions():
        listeners.notify_added(name, kind, Registration.SUB)
    for name, uri in get_service_manager().get_services():
        listeners.notify_added(name, uri, Registration.SRV)


@contextlib.contextmanager
def signals_held() -> Iterator[None]:
    """Hold SIGINT and SIGTERM while the node registers, and deliver them after.

    rospy's signal handler unregisters through the same locked master proxy that a registration
    in progress holds: a Ctrl-C that lands inside one (the node registers a dozen topics and
    services at start) deadlocks the node for good (seen: rospy.core _LockedServerProxy, called
    from RegManager.cleanup inside RegManager.reg_added)."""
    held: List[int] = []
    previous = {sig: signal.signal(sig, lambda number, frame: held.append(number)) for sig in _HELD}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        for number in held:
            os.kill(os.getpid(), number)


_HELD = (signal.SIGINT, signal.SIGTERM)


def announce_start(started_at: float) -> None:
    """Say when the node started (~start_time): a real-time replay lines its scenario clock up with
    the node's health checks, which count from there."""
    rospy.set_param("~start_time", started_at)


def wait_for_shutdown() -> None:
    """Block until ROS shuts the node down (SIGINT, rosnode kill, the master going away)."""
    rospy.spin()
