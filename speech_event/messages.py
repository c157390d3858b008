"""Plain-Python messages shaped like the std_msgs types the node speaks.

Their attribute names match rospy's generated classes (``layout.dim``, ``data``, ``_type``),
so the node's logic reads a rospy message and one of these the same way.
"""

from dataclasses import dataclass, field
from typing import ClassVar, Sequence, Tuple, Union

import numpy as np


@dataclass(frozen=True)
class MultiArrayDimension:
    """std_msgs/MultiArrayDimension: one dimension of a multi-array's layout."""

    label: str = ""
    size: int = 0
    stride: int = 0


@dataclass(frozen=True)
class MultiArrayLayout:
    """std_msgs/MultiArrayLayout: a multi-array's dimensions (none for soundDetection's mono audio)."""

    dim: Tuple[MultiArrayDimension, ...] = ()
    data_offset: int = 0


@dataclass
class Float32MultiArray:
    """What soundDetection publishes: mono float32 samples, layout left empty."""

    _type: ClassVar[str] = "std_msgs/Float32MultiArray"
    data: Union[np.ndarray, Sequence[float]] = ()
    layout: MultiArrayLayout = field(default_factory=MultiArrayLayout)


@dataclass
class String:
    """What the node publishes on /speechEvent/text."""

    _type: ClassVar[str] = "std_msgs/String"
    data: str = ""


# What /speechEvent/transcript carries for a text without an engine's confidence, and for a text
# of no utterance (an error such as SOUND_DETECTION_DOWN): its first_block and last_block.
NO_CONFIDENCE = -1.0
NO_UTTERANCE = 0.0


@dataclass(frozen=True)
class TranscriptMessage:
    """speech_event/Transcript (msg/Transcript.msg): one partial or final text with its confidence,
    language, engine and the times of its utterance's first and last blocks. Times are seconds on
    the node's clock; the ROS adapter makes ``stamp`` the header's stamp."""

    _type: ClassVar[str] = "speech_event/Transcript"
    stamp: float
    text: str
    final: bool
    confidence: float  # the engine's, 0 to 1; NO_CONFIDENCE when it reports none
    language: str
    engine: str
    first_block: float
    last_block: float


def message_type_name(message: object) -> str:
    """The ROS type name of a message, or its Python class name when it has none."""
    return str(getattr(message, "_type", type(message).__name__))


# -- the services the Behaviour Controller calls (srv/SetEnabled.srv, SetLanguage.srv, SetGrammar.srv)


@dataclass(frozen=True)
class SetEnabledRequest:
    """The request of speech_event/SetEnabled (srv/SetEnabled.srv): ``status``, true or false."""

    status: str = ""


@dataclass(frozen=True)
class SetEnabledResponse:
    """The response of speech_event/SetEnabled: 1 accepted, 0 rejected."""

    response: int = 0  # int8: 1 accepted, 0 rejected


@dataclass(frozen=True)
class SetLanguageRequest:
    """The request of speech_event/SetLanguage (srv/SetLanguage.srv): ``language``, english or kinyarwanda."""

    language: str = ""


@dataclass(frozen=True)
class SetLanguageResponse:
    """The response of speech_event/SetLanguage: 1 accepted, 0 rejected."""

    response: int = 0  # int8: 1 accepted, 0 rejected


@dataclass(frozen=True)
class SetGrammarRequest:
    """The request of speech_event/SetGrammar (srv/SetGrammar.srv): ``grammar``, a file, phrases
    parted by |, or empty for free speech."""

    grammar: str = ""


@dataclass(frozen=True)
class SetGrammarResponse:
    """The response of speech_event/SetGrammar: 1 accepted, 0 rejected."""

    response: int = 0  # int8: 1 accepted, 0 rejected


@dataclass(frozen=True)
class ServiceType:
    """A service definition: the ROS type name and the request and response classes."""

    name: str
    request: type
    response: type


SET_ENABLED = ServiceType("speech_event/SetEnabled", SetEnabledRequest, SetEnabledResponse)
SET_LANGUAGE = ServiceType("speech_event/SetLanguage", SetLanguageRequest, SetLanguageResponse)
SET_GRAMMAR = ServiceType("speech_event/SetGrammar", SetGrammarRequest, SetGrammarResponse)


# -- the action (action/RecogniseSpeech.action) ----------------------------------------------------


@dataclass(frozen=True)
class RecogniseSpeechGoal:
    """speech_event/RecogniseSpeechGoal (action/RecogniseSpeech.action): how long to wait for speech."""

    wait: float = 0.0  # float32: seconds to wait for speech to start


@dataclass(frozen=True)
class RecogniseSpeechResult:
    """speech_event/RecogniseSpeechResult: the text published for the utterance; empty when none."""

    transcription: str = ""


@dataclass(frozen=True)
class RecogniseSpeechFeedback:
    """speech_event/RecogniseSpeechFeedback: progress, 0 to 100."""

    progress: int = 0  # int8: 0 to 100


@dataclass(frozen=True)
class ActionType:
    """An action definition: the ROS type name and the goal, result and feedback classes."""

    name: str
    goal: type
    result: type
    feedback: type


RECOGNISE_SPEECH = ActionType(
    "speech_event/RecogniseSpeech", RecogniseSpeechGoal, RecogniseSpeechResult, RecogniseSpeechFeedback
)


# -- /diagnostics (diagnostic_msgs/DiagnosticArray) -------------------------------------------------


@dataclass(frozen=True)
class KeyValue:
    """diagnostic_msgs/KeyValue: one named value of a diagnostic status."""

    key: str
    value: str


@dataclass(frozen=True)
class DiagnosticStatus:
    """diagnostic_msgs/DiagnosticStatus: a level (OK, WARN, ERROR), a message and key-values."""

    OK: ClassVar[int] = 0
    WARN: ClassVar[int] = 1
    ERROR: ClassVar[int] = 2

    level: int
    name: str
    message: str
    hardware_id: str = ""
    values: Tuple[KeyValue, ...] = ()


@dataclass(frozen=True)
class DiagnosticArray:
    """diagnostic_msgs/DiagnosticArray, its header reduced to the stamp."""

    _type: ClassVar[str] = "diagnostic_msgs/DiagnosticArray"
    stamp: float  # seconds on the node's clock; the ROS adapter makes it the header's stamp
    status: Tuple[DiagnosticStatus, ...] = ()
