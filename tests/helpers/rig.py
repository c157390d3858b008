"""The node on the in-memory bus with a fake clock: what tests drive and what they read back."""

from typing import Callable, List, Optional, Tuple

import numpy as np

from speech_event import SIGNAL_TOPIC, TEXT_TOPIC
from speech_event.adapters.executors import ClockExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus, MemoryPublisher
from speech_event.config import SpeechEventConfig
from speech_event.interfaces.diagnostics import DIAGNOSTICS_TOPIC
from speech_event.messages import DiagnosticArray, Float32MultiArray, String
from speech_event.node import SpeechEventNode
from speech_event.ports import EngineBuilder, Executor, Recognizer


class Rig:
    """The node on the in-memory bus with a fake clock, and what it published."""

    def __init__(
        self,
        config: SpeechEventConfig,
        recognizer: Recognizer,
        executor: Optional[Executor] = None,
        build_engine: Optional[EngineBuilder] = None,
        job_seconds: float = 0.0,
        stopwatch: Optional[Callable[[], float]] = None,
        clock: Optional[FakeClock] = None,
    ) -> None:
        self.clock = clock or FakeClock()
        self.bus = InMemoryBus()
        self.published: List[Tuple[float, str]] = []
        self.diagnostics: List[DiagnosticArray] = []
        self.bus.subscribe(TEXT_TOPIC, String, self._record)
        self.bus.subscribe(DIAGNOSTICS_TOPIC, DiagnosticArray, self.diagnostics.append)  # type: ignore[arg-type]
        self.executor = executor or ClockExecutor(self.clock, job_seconds)
        self.node = SpeechEventNode(
            config,
            self.bus,
            self.clock,
            recognizer,
            self.executor,
            build_engine,
            stopwatch=stopwatch or self.clock.now,
        )
        self.sound_detection: MemoryPublisher = self.bus.advertise(
            SIGNAL_TOPIC, Float32MultiArray, node="soundDetection"
        )
        self.node.start()

    def _record(self, message: object) -> None:
        self.published.append((self.clock.now(), message.data))  # type: ignore[attr-defined]

    def speak(self, samples: np.ndarray, block: int = 4096) -> None:
        for start in range(0, samples.size, block):
            self.clock.advance(block / 16000)
            self.sound_detection.publish(Float32MultiArray(data=samples[start : start + block]))

    def texts(self) -> List[str]:
        return [text for _, text in self.published]


AT_16K = SpeechEventConfig(sample_rate=16000, health_check_period=3600.0)
