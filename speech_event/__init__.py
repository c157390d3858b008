"""Speech Event: the speech-to-text node of the CSSR4Africa robot.

The node transcribes audio from ``/soundDetection/signal`` and publishes the text on
``/speechEvent/text``. Its core depends on numpy and four ports (``Transport``, ``Clock``,
``Recognizer``, ``Executor``), so the same code runs on an in-memory bus with a fake clock, on a
real roscore, and on the robot. What a program embedding the node needs is here; deeper module
paths may move::

    import speech_event as se

    config = se.SpeechEventConfig(sample_rate=16000)
    bus, clock = se.InMemoryBus(), se.FakeClock()
    node = se.SpeechEventNode(config, bus, clock, se.RECOGNIZERS["fake"](config), se.ClockExecutor(clock))
    node.start()
    bus.subscribe(se.TEXT_TOPIC, se.String, print)
    sound_detection = bus.advertise(se.SIGNAL_TOPIC, se.Float32MultiArray, node="soundDetection")
    # publish Float32MultiArray blocks on it, advance the clock past speech_pause_period
"""

import importlib
from typing import TYPE_CHECKING, Any, Dict, List, Tuple

if TYPE_CHECKING:  # for type checkers (``X as X``: re-exported); at run time, see _PUBLIC
    from speech_event.adapters.executors import ClockExecutor as ClockExecutor
    from speech_event.adapters.executors import ThreadExecutor as ThreadExecutor
    from speech_event.adapters.fake_clock import FakeClock as FakeClock
    from speech_event.adapters.memory_bus import InMemoryBus as InMemoryBus
    from speech_event.adapters.system_clock import SystemClock as SystemClock
    from speech_event.config import SpeechEventConfig as SpeechEventConfig
    from speech_event.config import apply_overrides as apply_overrides
    from speech_event.config import load_config as load_config
    from speech_event.config import parse_config as parse_config
    from speech_event.errors import ConfigError as ConfigError
    from speech_event.errors import GrammarError as GrammarError
    from speech_event.errors import ModelError as ModelError
    from speech_event.errors import StorageError as StorageError
    from speech_event.grammar import Grammar as Grammar
    from speech_event.grammar import load_grammar as load_grammar
    from speech_event.grammar import requested_grammar as requested_grammar
    from speech_event.messages import RECOGNISE_SPEECH as RECOGNISE_SPEECH
    from speech_event.messages import SET_ENABLED as SET_ENABLED
    from speech_event.messages import SET_GRAMMAR as SET_GRAMMAR
    from speech_event.messages import SET_LANGUAGE as SET_LANGUAGE
    from speech_event.messages import DiagnosticArray as DiagnosticArray
    from speech_event.messages import DiagnosticStatus as DiagnosticStatus
    from speech_event.messages import Float32MultiArray as Float32MultiArray
    from speech_event.messages import KeyValue as KeyValue
    from speech_event.messages import MultiArrayDimension as MultiArrayDimension
    from speech_event.messages import MultiArrayLayout as MultiArrayLayout
    from speech_event.messages import RecogniseSpeechFeedback as RecogniseSpeechFeedback
    from speech_event.messages import RecogniseSpeechGoal as RecogniseSpeechGoal
    from speech_event.messages import RecogniseSpeechResult as RecogniseSpeechResult
    from speech_event.messages import SetEnabledRequest as SetEnabledRequest
    from speech_event.messages import SetEnabledResponse as SetEnabledResponse
    from speech_event.messages import SetGrammarRequest as SetGrammarRequest
    from speech_event.messages import SetGrammarResponse as SetGrammarResponse
    from speech_event.messages import SetLanguageRequest as SetLanguageRequest
    from speech_event.messages import SetLanguageResponse as SetLanguageResponse
    from speech_event.messages import String as String
    from speech_event.messages import TranscriptMessage as TranscriptMessage
    from speech_event.node import SpeechEventNode as SpeechEventNode
    from speech_event.ports import ActionGoal as ActionGoal
    from speech_event.ports import Audio as Audio
    from speech_event.ports import Cancellable as Cancellable
    from speech_event.ports import Clock as Clock
    from speech_event.ports import ClosesSentences as ClosesSentences
    from speech_event.ports import Executor as Executor
    from speech_event.ports import Grammars as Grammars
    from speech_event.ports import Incremental as Incremental
    from speech_event.ports import Publisher as Publisher
    from speech_event.ports import PublisherStatus as PublisherStatus
    from speech_event.ports import Received as Received
    from speech_event.ports import Recognizer as Recognizer
    from speech_event.ports import Stoppable as Stoppable
    from speech_event.ports import Timer as Timer
    from speech_event.ports import Transcript as Transcript
    from speech_event.ports import Transport as Transport
    from speech_event.recognizers import RECOGNIZERS as RECOGNIZERS
    from speech_event.recognizers import RecognizerFactory as RecognizerFactory
    from speech_event.recognizers import engine_builder as engine_builder
    from speech_event.topics import PARTIAL_TOPIC as PARTIAL_TOPIC
    from speech_event.topics import SIGNAL_TOPIC as SIGNAL_TOPIC
    from speech_event.topics import SOUND_DETECTION_DOWN as SOUND_DETECTION_DOWN
    from speech_event.topics import SPEECH_NOT_RECOGNIZED as SPEECH_NOT_RECOGNIZED
    from speech_event.topics import TEXT_TOPIC as TEXT_TOPIC
    from speech_event.topics import TRANSCRIPT_TOPIC as TRANSCRIPT_TOPIC

# The public names by the module each comes from, imported on first use so that importing
# speech_event (or the ROS classes genpy builds in it, speech_event.srv and speech_event.msg, as
# rosservice does under the system Python) needs no numpy. The same names as the TYPE_CHECKING
# imports above: tests/test_public_api.py keeps the two equal.
_PUBLIC: Dict[str, Tuple[str, ...]] = {
    "speech_event.adapters.executors": ("ClockExecutor", "ThreadExecutor"),
    "speech_event.adapters.fake_clock": ("FakeClock",),
    "speech_event.adapters.memory_bus": ("InMemoryBus",),
    "speech_event.adapters.system_clock": ("SystemClock",),
    "speech_event.config": ("SpeechEventConfig", "apply_overrides", "load_config", "parse_config"),
    "speech_event.errors": ("ConfigError", "GrammarError", "ModelError", "StorageError"),
    "speech_event.grammar": ("Grammar", "load_grammar", "requested_grammar"),
    "speech_event.messages": (
        "RECOGNISE_SPEECH",
        "SET_ENABLED",
        "SET_GRAMMAR",
        "SET_LANGUAGE",
        "DiagnosticArray",
        "DiagnosticStatus",
        "Float32MultiArray",
        "KeyValue",
        "MultiArrayDimension",
        "MultiArrayLayout",
        "RecogniseSpeechFeedback",
        "RecogniseSpeechGoal",
        "RecogniseSpeechResult",
        "SetEnabledRequest",
        "SetEnabledResponse",
        "SetGrammarRequest",
        "SetGrammarResponse",
        "SetLanguageRequest",
        "SetLanguageResponse",
        "String",
        "TranscriptMessage",
    ),
    "speech_event.node": ("SpeechEventNode",),
    "speech_event.ports": (
        "ActionGoal",
        "Audio",
        "Cancellable",
        "Clock",
        "ClosesSentences",
        "Executor",
        "Grammars",
        "Incremental",
        "Publisher",
        "PublisherStatus",
        "Received",
        "Recognizer",
        "Stoppable",
        "Timer",
        "Transcript",
        "Transport",
    ),
    "speech_event.recognizers": ("RECOGNIZERS", "RecognizerFactory", "engine_builder"),
    "speech_event.topics": (
        "PARTIAL_TOPIC",
        "SIGNAL_TOPIC",
        "SOUND_DETECTION_DOWN",
        "SPEECH_NOT_RECOGNIZED",
        "TEXT_TOPIC",
        "TRANSCRIPT_TOPIC",
    ),
}
_EXPORTS: Dict[str, str] = {name: module for module, names in _PUBLIC.items() for name in names}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    """The public name ``name``, imported from its module the first time it is asked for."""
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'speech_event' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> List[str]:
    """The public names."""
    return __all__
