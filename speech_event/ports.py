"""The ports the node depends on: ``Transport``, ``Clock``, ``Recognizer`` and the ``Executor``.

Adapters implement these: the in-memory bus and the rospy transport, the fake and ROS clocks,
the recognition engines and their fakes, the simulated and threaded workers. What only some
engines can do is a Protocol of its own (``Stoppable``, ``Grammars``, ``Incremental``,
``ClosesSentences``, ``Hosted``), checked with ``isinstance``: an engine has the ability by having its method.
"""

import enum
from dataclasses import dataclass
from typing import Callable, Optional, Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from speech_event.grammar import Grammar
from speech_event.messages import ActionType, ServiceType


class PublisherStatus(enum.Enum):
    """What the transport knows about the publishers of a topic."""

    NONE = "no publisher registered"
    STALE = "publisher registered but no live connection"
    CONNECTED = "publisher connected"
    # The ROS master did not answer in time: the subscriber's live connections alone tell.
    CONNECTED_MASTER_SILENT = "publisher connected (the ROS master did not answer: from the live connection)"
    NONE_MASTER_SILENT = "no live connection (the ROS master did not answer)"

    @property
    def up(self) -> bool:
        return self in (PublisherStatus.CONNECTED, PublisherStatus.CONNECTED_MASTER_SILENT)


class Publisher(Protocol):
    """Publishes messages on the topic it was advertised for."""

    def publish(self, message: object) -> None: ...


class ActionGoal(Protocol):
    """One goal of an action, as its server sees it (actionlib's ServerGoalHandle)."""

    @property
    def goal(self) -> object: ...

    def accept(self) -> None: ...

    def feedback(self, feedback: object) -> None: ...

    def succeed(self, result: object) -> None: ...

    def abort(self, result: object) -> None: ...

    def cancel(self, result: object) -> None:
        """End an accepted goal as preempted (a cancel request, or a newer goal took its place)."""
        ...


class Transport(Protocol):
    """Topics, services and actions: what the node needs of ROS (RosTransport, InMemoryBus)."""

    def advertise(self, topic: str, message_type: type) -> Publisher: ...

    def subscribe(self, topic: str, message_type: type, callback: Callable[[object], None]) -> None: ...

    def publisher_status(self, topic: str) -> PublisherStatus: ...

    def serve(self, name: str, service: ServiceType, handler: Callable[[object], object]) -> None:
        """Answer calls of service ``name``: ``handler`` takes a request and returns the response."""
        ...

    def serve_action(
        self,
        name: str,
        action: ActionType,
        on_goal: Callable[[ActionGoal], None],
        on_cancel: Callable[[ActionGoal], None],
    ) -> None:
        """Serve action ``name``: ``on_goal`` for each new goal, ``on_cancel`` for a cancel request."""
        ...


@runtime_checkable
class Received(Protocol):
    """A message its transport stamped, on the node's clock, when it read it off the wire (rospy:
    before the callback, which may wait for the node's lock). A message without one arrived when
    its callback runs (the in-memory bus calls back at once)."""

    received_at: float


class Timer(Protocol):
    """A callback set on a Clock; ``cancel`` keeps it from running."""

    def cancel(self) -> None: ...


# A timer may fire a little early (RosClock fires 0.1 ms early against nanosecond rounding): a
# timer that fires within this of its time has come due. Every check "is it time yet?" made from a
# timer's callback allows for it.
TIMER_TOLERANCE = 1e-3


class Clock(Protocol):
    """The node's time line (ROS time on the robot) and its timers."""

    def now(self) -> float:
        """Seconds on this clock's time line."""
        ...

    def call_at(self, when: float, callback: Callable[[], None]) -> Timer:
        """Run ``callback`` once when the clock reaches ``when`` (up to TIMER_TOLERANCE early)."""
        ...


class Cancellable(Protocol):
    """A job submitted to an Executor."""

    def cancel(self) -> None:
        """Do not run the job if it has not started (a started one runs on)."""
        ...


class Executor(Protocol):
    """Runs jobs off the subscriber callback, one at a time, in submission order."""

    def submit(self, job: Callable[[], None]) -> Cancellable:
        """Run ``job`` after every job submitted before it."""
        ...


# Mono audio samples in [-1, 1]: what the node assembles and the engines transcribe.
Audio = npt.NDArray[np.float32]


@dataclass(frozen=True)
class Transcript:
    """What an engine made of one utterance."""

    text: str
    # In [0, 1] when the engine reports one; None when it does not.
    confidence: Optional[float] = None
    # With a grammar in force: the grammar's best phrase when the speech was judged to be none of
    # its phrases (the text is then empty), for the log and the out-of-grammar count.
    rejected: Optional[str] = None


class Recognizer(Protocol):
    """A speech engine: one utterance of audio in, its transcript out."""

    @property
    def sample_rate(self) -> int:
        """The rate, in Hz, of the audio ``transcribe`` expects."""
        ...

    def transcribe(self, audio: Audio) -> Transcript:
        """Transcribe one utterance of mono float32 audio at ``sample_rate``."""
        ...


# language -> its engine; raises ModelError (with what is wrong) when it cannot be built.
EngineBuilder = Callable[[str], Recognizer]


@runtime_checkable
class Stoppable(Protocol):
    """An engine whose running ``transcribe`` another thread can stop (recognition_timeout, and
    speculation, which only runs on such an engine)."""

    def stop(self) -> None:
        """Stop the transcribe running now: it raises instead of answering."""
        ...


@runtime_checkable
class Grammars(Protocol):
    """An engine that decodes within a command grammar: with one in force, every text it gives is a
    whole phrase of it, and speech that is none of its phrases gives no text (``rejected``)."""

    def check_grammar(self, grammar: Grammar) -> None:
        """GrammarError saying why this engine cannot use ``grammar`` (words it cannot spell, a
        grammar of too many sentences), before anything is switched."""
        ...

    def use_grammar(self, grammar: Optional[Grammar]) -> None:
        """Decode within ``grammar`` from the next ``transcribe`` on; None: free speech again."""
        ...


@runtime_checkable
class Incremental(Protocol):
    """An engine that decodes a growing utterance on a decoder of its own, fed only the audio that
    is new (pocketsphinx): partial results cost only the new audio and never touch the decoding
    of final texts. Called on the recognition worker only, as ``transcribe`` is."""

    @property
    def sample_rate(self) -> int:
        """The rate, in Hz, of the audio ``feed_partial`` expects."""
        ...

    def begin_partial(self, grammar: Optional[Grammar]) -> None:
        """A new utterance on the partial decoder, within ``grammar`` (None: free speech); the
        utterance before it, if any, is abandoned."""
        ...

    def feed_partial(self, audio: Audio) -> Transcript:
        """The next samples of the utterance (at ``sample_rate``): the text of all of it so far."""
        ...


@runtime_checkable
class ClosesSentences(Protocol):
    """An engine that writes case and punctuation (Whisper): a finished sentence ends with a full
    stop, question or exclamation mark, so its text says where a speaker may be done, and the
    turn-end model's default (``turn_end_model auto``) listens with it in English."""

    def closes_sentences(self) -> bool:
        """True: the texts of this engine close the sentences they finish."""
        ...


@runtime_checkable
class Hosted(Protocol):
    """An engine that runs another in a process of its own (speech_event/recognizers/hosted.py)."""

    @property
    def hosts(self) -> str:
        """The class name of the engine it runs."""
        ...


def engine_name(engine: object) -> str:
    """What transcripts, stored utterances and logs call an engine: its class's name; for a Hosted
    one, the name of the engine it runs, as when that runs in the node's process."""
    return engine.hosts if isinstance(engine, Hosted) else type(engine).__name__
