"""The driver's link to /soundDetection/signal (harness/driver_node.py), the same on ROS and on
the in-memory bus."""

from typing import Any, Callable, Optional

from speech_event.ports import Publisher


class Link:
    """soundDetection's presence on the topic: up (a publisher), or down (none)."""

    def __init__(self, advertise: Callable[[], Any], wait_for_subscriber: Callable[[Any], None]) -> None:
        self._advertise = advertise
        self._wait = wait_for_subscriber
        self.publisher: Optional[Any] = None

    def up(self) -> Publisher:
        publisher: Publisher = self._advertise()
        self._wait(publisher)  # messages sent before a subscriber connects are lost
        self.publisher = publisher
        return publisher

    def down(self, crash: bool) -> None:
        if self.publisher is not None:
            # The in-memory bus can crash a publisher (a stale registration); rospy only unregisters.
            stop = (
                getattr(self.publisher, "crash" if crash else "shutdown", None) or self.publisher.unregister
            )
            stop()
            self.publisher = None
