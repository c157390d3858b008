"""An in-memory topic bus: the Transport port with no ROS, for tests and scenario replay.

Delivery is synchronous and in subscription order. Like the ROS master, it keeps publisher
registrations per node name, so a publisher can leave cleanly (``shutdown``) or die leaving its
registration behind (``crash``), and a node that comes back replaces its own stale registration.
"""

from collections import defaultdict
from typing import Callable, DefaultDict, Dict, List

from speech_event.ports import PublisherStatus


class MemoryPublisher:
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


class InMemoryBus:
    def __init__(self) -> None:
        self._subscribers: DefaultDict[str, List[Callable[[object], None]]] = defaultdict(list)
        self._publishers: DefaultDict[str, Dict[str, MemoryPublisher]] = defaultdict(dict)

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
