"""The three ports the node depends on (plus the executor it is handed).

Adapters implement these: the in-memory bus and the rospy transport, the fake and ROS clocks,
the recognition engines and their fakes.
"""

import enum
from dataclasses import dataclass
from typing import Callable, Optional, Protocol

import numpy as np


class PublisherStatus(enum.Enum):
    """What the transport knows about the publishers of a topic."""

    NONE = "no publisher registered"
    STALE = "publisher registered but no live connection"
    CONNECTED = "publisher connected"


class Publisher(Protocol):
    def publish(self, message: object) -> None: ...


class Transport(Protocol):
    def advertise(self, topic: str, message_type: type) -> Publisher: ...

    def subscribe(self, topic: str, message_type: type, callback: Callable[[object], None]) -> None: ...

    def publisher_status(self, topic: str) -> PublisherStatus: ...


class Timer(Protocol):
    def cancel(self) -> None: ...


class Clock(Protocol):
    def now(self) -> float:
        """Seconds on this clock's time line."""
        ...

    def call_at(self, when: float, callback: Callable[[], None]) -> Timer:
        """Run ``callback`` once when the clock reaches ``when``."""
        ...


class Executor(Protocol):
    """Runs jobs off the subscriber callback, one at a time, in submission order."""

    def submit(self, job: Callable[[], None]) -> None: ...


@dataclass(frozen=True)
class Transcript:
    text: str
    # In [0, 1] when the engine reports one; None when it does not.
    confidence: Optional[float] = None


class Recognizer(Protocol):
    @property
    def sample_rate(self) -> int:
        """The rate, in Hz, of the audio ``transcribe`` expects."""
        ...

    def transcribe(self, audio: np.ndarray) -> Transcript:
        """Transcribe one utterance of mono float32 audio at ``sample_rate``."""
        ...
