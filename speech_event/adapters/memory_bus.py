"""An in-memory topic bus: the Transport port with no ROS, for tests and scenario replay.

Delivery is synchronous and in subscription order. Like the ROS master, it keeps publisher
registrations per node name, so a publisher can leave cleanly (``shutdown``) or die leaving its
registration behind (``crash``), and a node that comes back replaces its own stale registration.
Services are called synchronously; action goals are tracked through actionlib's states.
"""

import threading
from collections import defaultdict
from typing import Callable, DefaultDict, Dict, List, Optional, Tuple

from speech_event.messages import ActionType, ServiceType
from speech_event.ports import ActionGoal, PublisherStatus


class MemoryPublisher:
    """One node's publisher on the bus, registered under the node's name; it can leave cleanly or crash."""

    def __init__(self, bus: "InMemoryBus", topic: str, node: str) -> None:
        self._bus = bus
        self.topic = topic
        self.node = node
        self.alive = True

    def publish(self, message: object) -> None:
        if not self.alive:
            raise RuntimeError(f"{self.node} published on {self.topic} after it went down")
        self._bus.deliver(self.topic, message)

    def shutdown(self) -> None:
        """Leave cleanly: the registration is removed."""
        self.alive = False
        self._bus.unregister(self)

    def crash(self) -> None:
        """Die without a word: the registration stays, the connection is gone."""
        self.alive = False


class MemoryGoal:
    """A goal sent on the bus: the server's handle (the ActionGoal port) and what its client sees.

    States are actionlib's, in lower case: pending, active, then one of succeeded, aborted,
    preempted (cancelled while active) or recalled (cancelled before it was accepted).
    """

    def __init__(self, goal: object, on_end: Callable[["MemoryGoal"], None]) -> None:
        self._goal = goal
        self._on_end = on_end
        self._lock = threading.Lock()
        self.state = "pending"
        self.result: Optional[object] = None
        self.feedbacks: List[object] = []

    @property
    def goal(self) -> object:
        return self._goal

    @property
    def done(self) -> bool:
        return self.state not in ("pending", "active")

    def accept(self) -> None:
        self._move(("pending",), "active")

    def feedback(self, feedback: object) -> None:
        with self._lock:
            if self.state != "active":
                raise RuntimeError(f"feedback on a goal that is {self.state}")
            self.feedbacks.append(feedback)

    def succeed(self, result: object) -> None:
        self._move(("active",), "succeeded", result)

    def abort(self, result: object) -> None:
        self._move(("active",), "aborted", result)

    def cancel(self, result: object) -> None:
        self._move(("active", "pending"), "preempted" if self.state == "active" else "recalled", result)

    def _move(self, allowed: Tuple[str, ...], state: str, result: Optional[object] = None) -> None:
        # actionlib logs and ignores a transition its state machine does not allow; a test
        # double should fail loudly instead, so a bug in the server shows.
        with self._lock:
            if self.state not in allowed:
                raise RuntimeError(f"a goal that is {self.state} cannot become {state}")
            self.state = state
            self.result = result
        if self.done:
            self._on_end(self)


class _ActionServer:
    def __init__(
        self, on_goal: Callable[[ActionGoal], None], on_cancel: Callable[[ActionGoal], None]
    ) -> None:
        self.on_goal = on_goal
        self.on_cancel = on_cancel


class InMemoryBus:
    """The Transport port in memory, and the clients' side: ``call`` a service, ``send_goal`` to an action."""

    def __init__(self) -> None:
        self._subscribers: DefaultDict[str, List[Callable[[object], None]]] = defaultdict(list)
        self._publishers: DefaultDict[str, Dict[str, MemoryPublisher]] = defaultdict(dict)
        self._services: Dict[str, Callable[[object], object]] = {}
        self._actions: Dict[str, _ActionServer] = {}
        self._goal_end_callbacks: List[Callable[[MemoryGoal], None]] = []

    def advertise(self, topic: str, message_type: type, node: str = "speechEvent") -> MemoryPublisher:
        publisher = MemoryPublisher(self, topic, node)
        self._publishers[topic][node] = publisher  # replaces this node's stale registration
        return publisher

    def subscribe(self, topic: str, message_type: type, callback: Callable[[object], None]) -> None:
        self._subscribers[topic].append(callback)

    def publisher_status(self, topic: str) -> PublisherStatus:
        registered = self._publishers[topic].values()
        if not registered:
            return PublisherStatus.NONE
        if any(publisher.alive for publisher in registered):
            return PublisherStatus.CONNECTED
        return PublisherStatus.STALE

    def deliver(self, topic: str, message: object) -> None:
        for callback in list(self._subscribers[topic]):
            callback(message)

    def unregister(self, publisher: MemoryPublisher) -> None:
        if self._publishers[publisher.topic].get(publisher.node) is publisher:
            del self._publishers[publisher.topic][publisher.node]

    # -- services ---------------------------------------------------------------------------------

    def serve(self, name: str, service: ServiceType, handler: Callable[[object], object]) -> None:
        self._services[name] = handler

    def call(self, name: str, request: object) -> object:
        """Call service ``name``, as rospy.ServiceProxy does: KeyError when nobody serves it."""
        return self._services[name](request)

    # -- actions ----------------------------------------------------------------------------------

    def serve_action(
        self,
        name: str,
        action: ActionType,
        on_goal: Callable[[ActionGoal], None],
        on_cancel: Callable[[ActionGoal], None],
    ) -> None:
        self._actions[name] = _ActionServer(on_goal, on_cancel)

    def send_goal(self, name: str, goal: object) -> MemoryGoal:
        """Send a goal to action ``name``; the returned object follows its state and result."""
        server = self._actions[name]
        handle = MemoryGoal(goal, self._goal_ended)
        server.on_goal(handle)
        return handle

    def on_goal_end(self, callback: Callable[[MemoryGoal], None]) -> None:
        """Call ``callback`` with each goal that ends, on any action, when it ends."""
        self._goal_end_callbacks.append(callback)

    def _goal_ended(self, goal: MemoryGoal) -> None:
        for callback in self._goal_end_callbacks:
            callback(goal)

    def cancel_goal(self, name: str, handle: MemoryGoal) -> None:
        if not handle.done:
            self._actions[name].on_cancel(handle)
