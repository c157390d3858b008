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
from typing import TYPE_CHECKING, Any, Dict, List

if TYPE_CHECKING:  # for type checkers; at run time each name is imported when first used
    from speech_event.adapters.executors import ClockExecutor, ThreadExecutor
    from speech_event.adapters.fake_clock import FakeClock
    from speech_event.adapters.memory_bus import InMemoryBus
    from speech_event.adapters.system_clock import SystemClock
    from speech_event.config import SpeechEventConfig, apply_overrides, load_config, parse_config
    from speech_event.errors import ConfigError, GrammarError, ModelError, StorageError
    from speech_event.grammar import Grammar, load_grammar, requested_grammar
    from speech_event.messages import (
        RECOGNISE_SPEECH,
        SET_ENABLED,
        SET_GRAMMAR,
        SET_LANGUAGE,
        DiagnosticArray,
        DiagnosticStatus,
        Float32MultiArray,
        KeyValue,
        MultiArrayDimension,
        MultiArrayLayout,
        RecogniseSpeechFeedback,
        RecogniseSpeechGoal,
        RecogniseSpeechResult,
        SetEnabledRequest,
        SetEnabledResponse,
        SetGrammarRequest,
        SetGrammarResponse,
        SetLanguageRequest,
        SetLanguageResponse,
        String,
        TranscriptMessage,
    )
    from speech_event.node import SpeechEventNode
    from speech_event.ports import (
        ActionGoal,
        Audio,
        Cancellable,
        Clock,
        Executor,
        Grammars,
        Incremental,
        Publisher,
        PublisherStatus,
        Recognizer,
        Stoppable,
        Timer,
        Transcript,
        Transport,
    )
    from speech_event.recognizers import RECOGNIZERS, RecognizerFactory, engine_builder
    from speech_event.topics import (
        PARTIAL_TOPIC,
        SIGNAL_TOPIC,
        SOUND_DETECTION_DOWN,
        SPEECH_NOT_RECOGNIZED,
        TEXT_TOPIC,
        TRANSCRIPT_TOPIC,
    )

# Imported on first use, so that importing speech_event (or the ROS classes genpy builds in it,
# speech_event.srv and speech_event.msg, as rosservice does under the system Python) needs no numpy.
_EXPORTS: Dict[str, str] = {
    "ActionGoal": "speech_event.ports",
    "apply_overrides": "speech_event.config",
    "Audio": "speech_event.ports",
    "Cancellable": "speech_event.ports",
    "Clock": "speech_event.ports",
    "ClockExecutor": "speech_event.adapters.executors",
    "ConfigError": "speech_event.errors",
    "DiagnosticArray": "speech_event.messages",
    "DiagnosticStatus": "speech_event.messages",
    "engine_builder": "speech_event.recognizers",
    "Executor": "speech_event.ports",
    "FakeClock": "speech_event.adapters.fake_clock",
    "Float32MultiArray": "speech_event.messages",
    "Grammar": "speech_event.grammar",
    "GrammarError": "speech_event.errors",
    "Grammars": "speech_event.ports",
    "Incremental": "speech_event.ports",
    "InMemoryBus": "speech_event.adapters.memory_bus",
    "KeyValue": "speech_event.messages",
    "load_config": "speech_event.config",
    "load_grammar": "speech_event.grammar",
    "ModelError": "speech_event.errors",
    "MultiArrayDimension": "speech_event.messages",
    "MultiArrayLayout": "speech_event.messages",
    "parse_config": "speech_event.config",
    "PARTIAL_TOPIC": "speech_event.topics",
    "Publisher": "speech_event.ports",
    "PublisherStatus": "speech_event.ports",
    "RECOGNISE_SPEECH": "speech_event.messages",
    "RecogniseSpeechFeedback": "speech_event.messages",
    "RecogniseSpeechGoal": "speech_event.messages",
    "RecogniseSpeechResult": "speech_event.messages",
    "Recognizer": "speech_event.ports",
    "RecognizerFactory": "speech_event.recognizers",
    "RECOGNIZERS": "speech_event.recognizers",
    "requested_grammar": "speech_event.grammar",
    "SET_ENABLED": "speech_event.messages",
    "SET_GRAMMAR": "speech_event.messages",
    "SET_LANGUAGE": "speech_event.messages",
    "SetEnabledRequest": "speech_event.messages",
    "SetEnabledResponse": "speech_event.messages",
    "SetGrammarRequest": "speech_event.messages",
    "SetGrammarResponse": "speech_event.messages",
    "SetLanguageRequest": "speech_event.messages",
    "SetLanguageResponse": "speech_event.messages",
    "SIGNAL_TOPIC": "speech_event.topics",
    "SOUND_DETECTION_DOWN": "speech_event.topics",
    "SPEECH_NOT_RECOGNIZED": "speech_event.topics",
    "SpeechEventConfig": "speech_event.config",
    "SpeechEventNode": "speech_event.node",
    "Stoppable": "speech_event.ports",
    "StorageError": "speech_event.errors",
    "String": "speech_event.messages",
    "SystemClock": "speech_event.adapters.system_clock",
    "TEXT_TOPIC": "speech_event.topics",
    "ThreadExecutor": "speech_event.adapters.executors",
    "Timer": "speech_event.ports",
    "Transcript": "speech_event.ports",
    "TRANSCRIPT_TOPIC": "speech_event.topics",
    "TranscriptMessage": "speech_event.messages",
    "Transport": "speech_event.ports",
}

__all__ = [
    "PARTIAL_TOPIC",
    "RECOGNISE_SPEECH",
    "RECOGNIZERS",
    "SET_ENABLED",
    "SET_GRAMMAR",
    "SET_LANGUAGE",
    "SIGNAL_TOPIC",
    "SOUND_DETECTION_DOWN",
    "SPEECH_NOT_RECOGNIZED",
    "TEXT_TOPIC",
    "TRANSCRIPT_TOPIC",
    "ActionGoal",
    "Audio",
    "Cancellable",
    "Clock",
    "ClockExecutor",
    "ConfigError",
    "DiagnosticArray",
    "DiagnosticStatus",
    "Executor",
    "FakeClock",
    "Float32MultiArray",
    "Grammar",
    "GrammarError",
    "Grammars",
    "InMemoryBus",
    "Incremental",
    "KeyValue",
    "ModelError",
    "MultiArrayDimension",
    "MultiArrayLayout",
    "Publisher",
    "PublisherStatus",
    "RecogniseSpeechFeedback",
    "RecogniseSpeechGoal",
    "RecogniseSpeechResult",
    "Recognizer",
    "RecognizerFactory",
    "SetEnabledRequest",
    "SetEnabledResponse",
    "SetGrammarRequest",
    "SetGrammarResponse",
    "SetLanguageRequest",
    "SetLanguageResponse",
    "SpeechEventConfig",
    "SpeechEventNode",
    "Stoppable",
    "StorageError",
    "String",
    "SystemClock",
    "ThreadExecutor",
    "Timer",
    "Transcript",
    "TranscriptMessage",
    "Transport",
    "apply_overrides",
    "engine_builder",
    "load_config",
    "load_grammar",
    "parse_config",
    "requested_grammar",
]


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
