"""The node as a state machine: any interleaving of blocks, bad messages and waits keeps every
accepted sample, in order, in exactly one utterance, and ends utterances only at pauses or at the
length limit."""

from typing import Dict, List, Set

import numpy as np
from hypothesis import settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, invariant, rule

from fixtures.fakes import SpyRecognizer
from fixtures.malformed import malformed_message
from fixtures.strategies import audio
from harness.scenario import MALFORMED_KINDS
from speech_event import SIGNAL_TOPIC
from speech_event.adapters.executors import ClockExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.config import SpeechEventConfig
from speech_event.messages import Float32MultiArray
from speech_event.node import SpeechEventNode
from speech_event.pipeline.assembly import search_samples
from speech_event.pipeline.validate import Reason, Rejection, validate_signal

CONFIG = SpeechEventConfig(
    sample_rate=16000,  # the recognizer's rate: no resampling, so samples can be compared exactly
    speech_pause_period=0.5,
    max_utterance_length=1.0,
    max_message_length=1.0,
    health_check_period=3600.0,
    # The recognizer here records what it is given: speculations would show the open utterance
    # to it too. Speculation publishes the same as without it (tests/turns/test_speculation.py).
    speculative_recognition=False,
)
LIMIT = int(CONFIG.max_utterance_length * CONFIG.sample_rate)
SEARCH = search_samples(LIMIT, CONFIG.sample_rate)


class NodeMachine(RuleBasedStateMachine):
    def __init__(self) -> None:
        super().__init__()
        self.clock = FakeClock()
        self.bus = InMemoryBus()
        self.recognizer = SpyRecognizer()
        self.node = SpeechEventNode(CONFIG, self.bus, self.clock, self.recognizer, ClockExecutor(self.clock))
        self.sound_detection = self.bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
        self.node.start()
        self.accepted: List[np.ndarray] = []
        self.accepted_total = 0
        self.last_arrival = 0.0
        self.pause_boundaries: Set[int] = set()
        self.rejected: Dict[str, int] = {reason.value: 0 for reason in Reason}
        self.rng = np.random.default_rng(0)

    @rule(samples=audio(max_samples=6000))
    def block(self, samples: np.ndarray) -> None:
        self.sound_detection.publish(Float32MultiArray(data=samples))
        self.clock.advance(0.0)  # run the recognition jobs this block completed
        self.accepted.append(samples)
        self.accepted_total += samples.size
        self.last_arrival = self.clock.now()

    @rule(kind=st.sampled_from(MALFORMED_KINDS))
    def malformed(self, kind: str) -> None:
        message = malformed_message(kind, CONFIG.sample_rate, CONFIG.max_message_length, self.rng)
        rejection = validate_signal(message, int(CONFIG.max_message_length * CONFIG.sample_rate))
        assert isinstance(rejection, Rejection)
        self.rejected[rejection.reason.value] += 1
        self.sound_detection.publish(message)

    @rule(seconds=st.floats(0.01, 1.0))
    def wait(self, seconds: float) -> None:
        self.clock.advance(seconds)
        if self.clock.now() >= self.last_arrival + CONFIG.speech_pause_period:
            self.pause_boundaries.add(self.accepted_total)

    @invariant()
    def every_accepted_sample_is_in_one_utterance_or_pending_in_order(self) -> None:
        recognized = self.recognizer.utterances
        total = sum(u.size for u in recognized)
        assert total + self.node.pending_samples == self.accepted_total
        if self.accepted:
            assert np.array_equal(
                np.concatenate(recognized) if recognized else np.zeros(0, np.float32),
                np.concatenate(self.accepted)[:total],
            )

    @invariant()
    def utterances_end_at_pauses_or_at_the_length_limit(self) -> None:
        ends = set(np.cumsum([u.size for u in self.recognizer.utterances]).tolist())
        recognized_total = max(ends, default=0)
        assert {b for b in self.pause_boundaries if 0 < b <= recognized_total} <= ends
        start = 0
        for utterance in self.recognizer.utterances:
            end = start + utterance.size
            assert utterance.size <= LIMIT
            if end not in self.pause_boundaries:
                assert utterance.size >= LIMIT - SEARCH
            start = end

    @invariant()
    def bad_messages_are_counted_per_reason(self) -> None:
        assert self.node.rejection_counts == self.rejected


NodeMachine.TestCase.settings = settings(max_examples=40, stateful_step_count=30, deadline=None)
TestNodeMachine = NodeMachine.TestCase
