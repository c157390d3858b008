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

from speech_event.adapters.executors import ClockExecutor, ThreadExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.adapters.system_clock import SystemClock
from speech_event.config import SpeechEventConfig, apply_overrides, load_config, parse_config
from speech_event.errors import ConfigError, ModelError, StorageError
from speech_event.messages import (
    RECOGNISE_SPEECH,
    SET_ENABLED,
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
    SetLanguageRequest,
    SetLanguageResponse,
    String,
)
from speech_event.node import SpeechEventNode
from speech_event.ports import (
    ActionGoal,
    Audio,
    Cancellable,
    Clock,
    Executor,
    Publisher,
    PublisherStatus,
    Recognizer,
    Stoppable,
    Timer,
    Transcript,
    Transport,
    WholePhrases,
)
from speech_event.recognizers import RECOGNIZERS, RecognizerFactory, engine_builder
from speech_event.topics import SIGNAL_TOPIC, SOUND_DETECTION_DOWN, SPEECH_NOT_RECOGNIZED, TEXT_TOPIC

__all__ = [
    "RECOGNISE_SPEECH",
    "RECOGNIZERS",
    "SET_ENABLED",
    "SET_LANGUAGE",
    "SIGNAL_TOPIC",
    "SOUND_DETECTION_DOWN",
    "SPEECH_NOT_RECOGNIZED",
    "TEXT_TOPIC",
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
    "InMemoryBus",
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
    "Transport",
    "WholePhrases",
    "apply_overrides",
    "engine_builder",
    "load_config",
    "parse_config",
]
