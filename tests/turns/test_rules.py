"""The turn rules behind their one entry (speech_event/turns/rules.py), without the node: blocks
taken, the pause on the fake clock, what goes to the worker and with what in force."""

import threading
from typing import List, Optional, Tuple

import numpy as np

from fixtures.fakes import SpyRecognizer
from speech_event.adapters.executors import ClockExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.config import SpeechEventConfig
from speech_event.grammar import Grammar, requested_grammar
from speech_event.interfaces.action import ListenAction
from speech_event.interfaces.diagnostics import NodeStatistics
from speech_event.pipeline.assembly import UtteranceAssembler
from speech_event.pipeline.publication import TextOrigin
from speech_event.pipeline.recognition_queue import RecognitionJob, RecognitionOutcome, RecognitionQueue
from speech_event.pipeline.watchdog import Watchdog
from speech_event.pipeline.worker import Worker
from speech_event.ports import Audio, Recognizer, Transcript
from speech_event.turns.rules import InForce, TurnRules

CONFIG = SpeechEventConfig(sample_rate=16000, speculative_recognition=False, partial_period=0.0)
BLOCK = np.full(4096, 0.1, dtype=np.float32)  # 0.256 s


class Concluded:
    """What the worker concluded: (utterance number, samples, grammar source or None)."""

    def __init__(self) -> None:
        self.said: List[Tuple[int, int, Optional[str]]] = []

    def conclude(self, job: RecognitionJob, outcome: RecognitionOutcome) -> None:
        self.said.append((job.number, job.audio.size, None if job.grammar is None else job.grammar.source))

    def dropped(self, job: RecognitionJob) -> None:
        raise AssertionError(f"utterance {job.number} dropped")

    def partial(self, transcript: Transcript, origin: TextOrigin) -> None:
        raise AssertionError("no partials are asked for")


def _recognize(audio: Audio, recognizer: Recognizer, grammar: Optional[Grammar]) -> RecognitionOutcome:
    return RecognitionOutcome(recognizer.transcribe(audio), took=0.0)


class LateTimers(FakeClock):
    def late_by(self, seconds: float) -> None:
        """``seconds`` pass while no timer fires: their thread is late (a busy machine)."""
        self._now += seconds


class Rig:
    def __init__(self) -> None:
        self.clock = LateTimers()
        lock = threading.Lock()
        self.in_force = InForce("english", SpyRecognizer(), None)
        self.concluded = Concluded()
        watchdog = Watchdog(self.clock, lock, 0.0, lambda job: False)
        worker = Worker(ClockExecutor(self.clock), _recognize, lambda: 0.0, self.concluded, watchdog)
        self.rules = TurnRules(
            CONFIG,
            self.clock,
            lock,
            self.in_force,
            UtteranceAssembler(16000, CONFIG.max_utterance_length),
            worker,
            RecognitionQueue(CONFIG.max_backlog),
            ListenAction(self.clock, lambda: None),
            NodeStatistics(),
        )

    def block_at(self, when: float) -> None:
        self.clock.advance_to(when)
        self.rules.take(BLOCK, when)


def test_the_pause_after_the_latest_block_hands_the_utterance_to_the_worker() -> None:
    rig = Rig()
    rig.block_at(0.0)
    rig.block_at(0.256)
    rig.clock.advance_to(0.256 + CONFIG.speech_pause_period - 0.01)
    assert rig.concluded.said == [] and rig.rules.pending_samples == 2 * BLOCK.size
    rig.clock.advance_to(0.256 + CONFIG.speech_pause_period + 0.01)
    assert rig.concluded.said == [(1, 2 * BLOCK.size, None)]
    assert rig.rules.utterances == 1 and rig.rules.pending_samples == 0


def test_a_grammar_set_after_the_pause_is_over_applies_to_the_next_utterance_only() -> None:
    rig = Rig()
    rig.block_at(0.0)
    # The pause is over, but the clock's timer has not run yet: the change of grammar ends the
    # utterance first, with what was in force while it was said.
    rig.clock.late_by(CONFIG.speech_pause_period + 0.5)
    rig.rules.engine_or_grammar_changes()
    rig.in_force.grammar = requested_grammar("yes|no")
    rig.block_at(CONFIG.speech_pause_period + 0.6)
    rig.clock.advance_to(10.0)
    assert rig.concluded.said == [(1, BLOCK.size, None), (2, BLOCK.size, "yes|no")]


def test_an_utterance_dropped_when_the_node_is_disabled_never_reaches_the_worker() -> None:
    rig = Rig()
    rig.block_at(0.0)
    rig.rules.drop_utterance()
    rig.clock.advance_to(5.0)
    assert rig.concluded.said == [] and rig.rules.pending_samples == 0
    rig.block_at(5.0)  # enabled again: the next utterance starts clean
    rig.clock.advance_to(10.0)
    assert rig.concluded.said == [(1, BLOCK.size, None)]
