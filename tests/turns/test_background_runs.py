"""The background runs alone (speech_event/turns/background_runs.py): when a speculation or a partial
result starts, is cancelled, adopted or dropped, and what its outcome becomes.

The node's side is stood in for: the utterance being collected and whether the worker is idle
(``Collecting``), turn-taking (``Turn``), an executor whose jobs run only when the test says
(``Jobs``), and a recorder of what is published. The clock is the fake one."""

import dataclasses
import threading
from typing import Callable, List, Optional, Tuple

import numpy as np
import pytest

from fixtures.fakes import SpyRecognizer
from speech_event.adapters.fake_clock import FakeClock, FakeTimer
from speech_event.config import SpeechEventConfig
from speech_event.grammar import Grammar, phrases_grammar
from speech_event.pipeline.publication import TextOrigin
from speech_event.pipeline.recognition_queue import RecognitionJob, RecognitionOutcome
from speech_event.pipeline.watchdog import Watchdog
from speech_event.pipeline.worker import Worker
from speech_event.ports import Audio, Recognizer, Transcript
from speech_event.turns.background_runs import BackgroundRuns, UtteranceSoFar
from speech_event.turns.partials import PartialCounts
from speech_event.turns.smart_turn import THREAD_NAME, HeardAlongside, TurnHeard
from speech_event.turns.speculation import SpeculationCounts

CONFIG = SpeechEventConfig(
    sample_rate=16000,
    speculative_recognition=True,
    partial_period=0.5,
    recognition_timeout=5.0,
    complete_answers="yes",
)
ORIGIN = TextOrigin("english", "Sizes", 0.0, 0.25)
TOOK = 0.25  # engine seconds of every recognition


class Sizes:
    """A Stoppable engine whose text is the number of samples it heard; ``during`` runs while it
    transcribes (what the node does meanwhile)."""

    sample_rate = 16000

    def __init__(self) -> None:
        self.heard: List[int] = []
        self.stops = 0
        self.during: Callable[[], None] = lambda: None

    def transcribe(self, audio: Audio) -> Transcript:
        self.heard.append(audio.size)
        self.during()
        return Transcript(f"{audio.size} samples")

    def stop(self) -> None:
        self.stops += 1


class Fed:
    """An Incremental engine that cannot be stopped: its partial decoder says how much it was fed."""

    sample_rate = 16000

    def __init__(self) -> None:
        self.calls: List[str] = []
        self._fed = 0

    def transcribe(self, audio: Audio) -> Transcript:
        return Transcript("final")

    def begin_partial(self, grammar: Optional[Grammar]) -> None:
        self.calls.append("begin")
        self._fed = 0

    def feed_partial(self, audio: Audio) -> Transcript:
        self.calls.append(f"feed {audio.size}")
        self._fed += audio.size
        return Transcript(f"fed {self._fed}")


class Jobs:
    """The worker: jobs wait until ``run_all``; a cancelled one never runs. A job's handle is a
    FakeTimer: its callback is the job."""

    def __init__(self) -> None:
        self.handles: List[FakeTimer] = []

    def submit(self, job: Callable[[], None]) -> FakeTimer:
        self.handles.append(FakeTimer(job))
        return self.handles[-1]

    @property
    def waiting(self) -> int:
        return sum(not handle.cancelled for handle in self.handles)

    def run_all(self) -> None:
        while self.handles:
            handle = self.handles.pop(0)
            if not handle.cancelled:
                handle.callback()


class Recorder:
    """What the runs published: ("conclude", utterance number, text) and ("partial", text, origin)."""

    def __init__(self) -> None:
        self.said: List[Tuple[object, ...]] = []

    def conclude(self, job: RecognitionJob, outcome: RecognitionOutcome) -> None:
        answer = outcome.answer
        self.said.append(("conclude", job.number, answer.text if isinstance(answer, Transcript) else None))

    def dropped(self, job: RecognitionJob) -> None:
        self.said.append(("dropped", job.number))

    def partial(self, transcript: Transcript, origin: TextOrigin) -> None:
        self.said.append(("partial", transcript.text, origin))


@dataclasses.dataclass
class Collecting:
    """The node's side: the utterance being collected (the engine in force), the worker's state."""

    engine: Recognizer
    audio: Audio = dataclasses.field(default_factory=lambda: np.zeros(0, dtype=np.float32))
    idle: bool = True
    grammar: Optional[Grammar] = None

    def add(self, samples: int) -> None:
        self.audio = np.concatenate([self.audio, np.full(samples, 0.1, dtype=np.float32)])

    def so_far(self) -> Optional[UtteranceSoFar]:
        if self.audio.size == 0:
            return None
        return UtteranceSoFar(self.audio.size, self.audio.copy, self.engine, self.grammar, ORIGIN)

    def job(self, number: int = 1) -> RecognitionJob:
        """The utterance collected so far, closed."""
        return RecognitionJob(number, 0.0, 1.0, 0.25, self.audio.copy(), self.engine, "english", 0.25)


@dataclasses.dataclass
class Turn:
    paused: bool = True  # the speaker has paused for speculation_gap
    ended_early: int = 0
    speculated_on: List[Tuple[int, bool]] = dataclasses.field(default_factory=list)  # samples, complete

    def gap_passed(self) -> bool:
        return self.paused

    def end_early(self) -> None:
        self.ended_early += 1

    def speculated(self, samples: int, complete: bool) -> None:
        self.speculated_on.append((samples, complete))


@dataclasses.dataclass
class Rig:
    runs: BackgroundRuns
    clock: FakeClock
    jobs: Jobs
    published: Recorder
    turn: Turn
    node: Collecting
    watchdog: Watchdog


def _recognize(audio: Audio, recognizer: Recognizer, grammar: Optional[Grammar]) -> RecognitionOutcome:
    return RecognitionOutcome(recognizer.transcribe(audio), took=TOOK)


def _sizes(rig: Rig) -> Sizes:
    assert isinstance(rig.node.engine, Sizes)
    return rig.node.engine


def _rig(
    engine: Optional[Recognizer] = None,
    config: SpeechEventConfig = CONFIG,
    turn_heard: Optional[TurnHeard] = None,
) -> Rig:
    clock, lock, jobs, published, turn = FakeClock(), threading.Lock(), Jobs(), Recorder(), Turn()
    node = Collecting(engine if engine is not None else Sizes())
    made: List[BackgroundRuns] = []  # the watchdog asks the runs, which are made after it
    watchdog = Watchdog(clock, lock, config.recognition_timeout, lambda job: made[0].running_for(job))
    worker = Worker(jobs, _recognize, lambda: 0.0, published, watchdog)
    runs = BackgroundRuns(config, clock, lock, worker, turn, node.so_far, lambda: node.idle, turn_heard)
    made.append(runs)
    return Rig(runs, clock, jobs, published, turn, node, watchdog)


def _speaking(
    engine: Optional[Recognizer] = None,
    config: SpeechEventConfig = CONFIG,
    paused: bool = True,
    turn_heard: Optional[TurnHeard] = None,
) -> Rig:
    """A rig whose utterance started at 0 s with one block of 4096 samples (the Sizes engine
    unless ``engine`` is given); its first partial is due at 0.5 s. ``paused``: the speaker has
    paused for speculation_gap. ``turn_heard``: the turn-end model."""
    rig = _rig(engine, config, turn_heard)
    rig.turn.paused = paused
    rig.node.add(4096)
    rig.runs.utterance_started(0.0)
    rig.runs.heard()
    return rig


def _partial_started(engine: Optional[Recognizer] = None) -> Rig:
    """A rig whose first partial started at 0.5 s, the speaker talking on (no speculation)."""
    rig = _speaking(engine, paused=False)
    rig.clock.advance(0.5)
    assert rig.runs.partials.started == 1
    return rig


# -- when a speculation starts ----------------------------------------------------------------------


def test_a_speculation_starts_once_the_speaker_paused_with_the_worker_idle() -> None:
    rig = _speaking()
    rig.runs.speculate()
    assert rig.jobs.waiting == 1
    rig.jobs.run_all()
    assert _sizes(rig).heard == [4096]
    assert rig.runs.speculations == SpeculationCounts(started=1, used=0, wasted_seconds=0.0)


@pytest.mark.parametrize(
    "what",
    ["the speaker has not paused", "the worker is busy", "nothing is collected", "the engine cannot stop"],
)
def test_no_speculation_starts_when(what: str) -> None:
    rig = _speaking(SpyRecognizer() if what == "the engine cannot stop" else None)
    rig.turn.paused = what != "the speaker has not paused"
    rig.node.idle = what != "the worker is busy"
    if what == "nothing is collected":
        rig.node.audio = np.zeros(0, dtype=np.float32)
    rig.runs.speculate()
    assert rig.jobs.waiting == 0
    assert rig.runs.speculations.started == 0


def test_no_second_speculation_starts_while_one_is_there() -> None:
    rig = _speaking()
    rig.runs.speculate()
    rig.runs.speculate()
    assert (rig.jobs.waiting, rig.runs.speculations.started) == (1, 1)


def test_a_speculation_cancels_the_partial_in_progress() -> None:
    rig = _partial_started()
    partial_run = rig.jobs.handles[0]
    rig.turn.paused = True
    rig.runs.speculate()
    assert partial_run.cancelled
    rig.jobs.run_all()
    assert _sizes(rig).heard == [4096]  # the speculation's only


# -- what cancels a speculation, and what becomes of its text ----------------------------------------


def test_a_block_cancels_the_speculation_before_it_runs() -> None:
    rig = _speaking()
    rig.runs.speculate()
    rig.runs.more_audio(None)
    assert rig.jobs.handles[0].cancelled
    assert _sizes(rig).stops == 0


def test_a_block_while_the_speculation_runs_stops_its_engine_and_its_time_is_wasted() -> None:
    rig = _speaking()
    _sizes(rig).during = lambda: rig.runs.more_audio(None)
    rig.runs.speculate()
    rig.jobs.run_all()
    assert _sizes(rig).stops == 1
    assert rig.published.said == []
    assert rig.runs.speculations == SpeculationCounts(started=1, used=0, wasted_seconds=TOOK)


def test_a_speculation_that_ends_with_the_utterance_going_on_is_a_partial_and_may_end_the_turn() -> None:
    rig = _speaking(config=dataclasses.replace(CONFIG, complete_answers="4096 samples"))
    rig.runs.speculate()
    rig.jobs.run_all()
    assert rig.published.said == [("partial", "4096 samples", ORIGIN)]
    assert rig.turn.ended_early == 1
    assert rig.runs.speculations == SpeculationCounts(started=1, used=0, wasted_seconds=0.0)


# -- the turn-end model, heard alongside the engine ------------------------------------------------

# The audio alone decides (turn_end_text false): any text is complete, and needs the model's verdict
# unless it is one of complete_answers.
HEARD = dataclasses.replace(CONFIG, turn_end_model="smart-turn", turn_end_text=False)
WAIT = 10.0  # seconds a thread waits for the other at most: in a passing run it never does


class Model:
    """A turn-end model that says ``verdict``, once ``release`` is set (at once unless the test
    clears it): what it was asked, and whether it answered."""

    def __init__(self, verdict: bool) -> None:
        self.verdict = verdict
        self.asked = threading.Event()
        self.release = threading.Event()
        self.release.set()
        self.answered = threading.Event()
        self.heard: List[Tuple[int, bool]] = []

    def wait_until_asked(self) -> None:
        self.asked.wait(WAIT)

    def __call__(self, audio: np.ndarray, paused: bool) -> bool:
        self.heard.append((audio.size, paused))
        self.asked.set()
        self.release.wait(WAIT)
        self.answered.set()
        return self.verdict


@pytest.mark.parametrize("verdict", [True, False])
def test_the_model_hears_the_speculations_audio_while_the_engine_transcribes_it(verdict: bool) -> None:
    model = Model(verdict)
    rig = _speaking(config=HEARD, turn_heard=model)
    asked_first: List[bool] = []
    _sizes(rig).during = lambda: asked_first.append(model.asked.wait(WAIT))  # one after the other: False
    rig.runs.speculate()
    rig.jobs.run_all()
    rig.runs.stop()
    assert asked_first == [True]
    assert model.heard == [(4096, True)]  # the audio ends at the last block: the gate's pause follows
    assert rig.turn.speculated_on == [(4096, verdict)]


def test_a_text_that_needs_no_verdict_does_not_wait_for_it() -> None:
    model = Model(verdict=False)
    model.release.clear()  # it answers only once the test lets it
    rig = _speaking(config=dataclasses.replace(HEARD, complete_answers="4096 samples"), turn_heard=model)
    try:
        _sizes(rig).during = model.wait_until_asked  # heard already: it cannot be dropped
        rig.runs.speculate()
        rig.jobs.run_all()
        assert rig.turn.speculated_on == [(4096, True)]  # one of complete_answers, whatever it says
        assert not model.answered.is_set()
    finally:
        model.release.set()
        rig.runs.stop()


def test_a_verdict_no_text_needs_is_dropped_unheard_when_it_has_not_started() -> None:
    model = Model(verdict=False)
    model.release.clear()  # the first verdict holds the thread
    config = dataclasses.replace(HEARD, complete_answers="4096 samples,8192 samples")
    rig = _speaking(config=config, turn_heard=model)
    try:
        _sizes(rig).during = model.wait_until_asked
        rig.runs.speculate()
        rig.jobs.run_all()
        rig.runs.more_audio(None)  # the speaker goes on
        rig.node.add(4096)
        rig.runs.speculate()
        rig.jobs.run_all()  # its verdict waits behind the first: dropped
        assert rig.turn.speculated_on == [(4096, True), (8192, True)]
    finally:
        model.release.set()
        rig.runs.stop()
    for thread in threading.enumerate():
        if thread.name.startswith(THREAD_NAME):
            thread.join(WAIT)  # once closed, the thread ends when it has heard what it was asked
    assert model.heard == [(4096, True)]


def test_with_a_grammar_in_force_the_model_is_not_asked() -> None:
    model = Model(verdict=False)
    rig = _speaking(config=HEARD, turn_heard=model)
    rig.node.grammar = phrases_grammar(["yes", "no"], "yes|no")
    rig.runs.speculate()
    rig.jobs.run_all()
    rig.runs.stop()
    assert model.heard == []
    assert rig.turn.speculated_on == [(4096, True)]


def test_once_closed_the_model_hears_nothing_more_and_no_turn_ends_early() -> None:
    model = Model(verdict=True)
    alongside = HeardAlongside(model)
    assert alongside.ask(np.zeros(1, np.float32), True).result(WAIT) is True
    alongside.close()
    verdict = alongside.ask(np.zeros(2, np.float32), False)
    assert verdict.done() and verdict.result() is False
    assert model.heard == [(1, True)]


def test_a_closed_utterance_adopts_the_running_speculation_on_its_audio_and_it_concludes_it() -> None:
    rig = _speaking()
    rig.runs.speculate()
    assert rig.runs.adopt(rig.node.job(7))
    rig.jobs.run_all()
    assert rig.published.said == [("conclude", 7, "4096 samples")]
    assert rig.turn.ended_early == 0
    assert rig.runs.speculations == SpeculationCounts(started=1, used=1, wasted_seconds=0.0)


def test_a_finished_speculation_adopted_concludes_its_utterance_on_the_clocks_next_turn() -> None:
    rig = _speaking()
    rig.runs.speculate()
    rig.jobs.run_all()
    assert rig.runs.adopt(rig.node.job(7))
    assert rig.published.said == [("partial", "4096 samples", ORIGIN)]
    rig.clock.advance(1.0)  # the job closed at 1.0 s
    assert rig.published.said == [("partial", "4096 samples", ORIGIN), ("conclude", 7, "4096 samples")]
    assert rig.jobs.waiting == 0  # not recognized again


def test_a_closed_utterance_of_other_audio_cancels_the_speculation_and_is_not_adopted() -> None:
    rig = _speaking()
    rig.runs.speculate()
    rig.node.add(10)
    assert not rig.runs.adopt(rig.node.job(7))
    assert rig.jobs.waiting == 0
    assert rig.published.said == []


def test_an_adopted_speculation_running_past_recognition_timeout_is_stopped() -> None:
    rig = _speaking()
    job = rig.node.job(7)

    def closes_and_overruns() -> None:  # the utterance closes while its speculation runs, 5 s long
        assert rig.runs.adopt(job)
        rig.clock.advance(CONFIG.recognition_timeout)

    _sizes(rig).during = closes_and_overruns
    rig.runs.speculate()
    rig.jobs.run_all()
    assert (rig.watchdog.timed_out, _sizes(rig).stops) == (1, 1)
    assert rig.published.said == [("conclude", 7, "4096 samples")]  # what the stopped run said


# -- when a partial starts --------------------------------------------------------------------------


def test_the_first_partial_is_due_a_period_after_the_first_block_and_publishes_its_text() -> None:
    rig = _speaking(paused=False)
    rig.clock.advance(0.49)
    assert rig.jobs.waiting == 0
    rig.clock.advance(0.01)
    rig.jobs.run_all()
    assert rig.published.said == [("partial", "4096 samples", ORIGIN)]
    assert rig.runs.partials == PartialCounts(started=1, published=1, worker_seconds=TOOK)


def test_a_partial_waits_for_the_worker_and_starts_when_it_is_free() -> None:
    rig = _speaking(paused=False)
    rig.node.idle = False
    rig.clock.advance(1.0)
    assert rig.jobs.waiting == 0
    rig.node.idle = True
    rig.runs.worker_free()
    assert (rig.jobs.waiting, rig.runs.partials.started) == (1, 1)


def test_a_partial_waits_while_a_speculation_is_there() -> None:
    rig = _speaking()
    rig.runs.speculate()
    rig.clock.advance(1.0)
    assert rig.runs.partials.started == 0


def test_a_partial_starts_again_only_when_due_and_on_more_audio() -> None:
    rig = _partial_started()
    rig.jobs.run_all()  # ends at 0.5 s: the next is due at 1.0 s
    rig.runs.partial()
    assert rig.runs.partials.started == 1  # not due
    rig.clock.advance(0.5)
    rig.runs.partial()
    assert rig.runs.partials.started == 1  # due, but no more audio
    rig.node.add(4096)
    rig.runs.more_audio(None)
    rig.runs.heard()
    rig.clock.advance(0.0)
    rig.jobs.run_all()
    assert [said[1] for said in rig.published.said] == ["4096 samples", "8192 samples"]


def test_more_audio_does_not_cancel_a_partial_run() -> None:
    rig = _partial_started()
    rig.runs.more_audio(None)
    assert not rig.jobs.handles[0].cancelled


def test_an_incremental_engine_is_fed_only_the_audio_new_since_its_last_partial() -> None:
    engine = Fed()
    rig = _partial_started(engine)
    rig.jobs.run_all()
    rig.node.add(1000)
    rig.runs.heard()
    rig.clock.advance(0.5)
    rig.jobs.run_all()
    # Chunks of 0.1 s (1600 samples) at 16 kHz.
    assert engine.calls == ["begin", "feed 1600", "feed 1600", "feed 896", "feed 1000"]
    assert [said[1] for said in rig.published.said] == ["fed 4096", "fed 5096"]


# -- what cancels a partial ---------------------------------------------------------------------------


def test_a_closed_utterance_cancels_the_partial_run_before_it_runs() -> None:
    rig = _partial_started()
    assert not rig.runs.adopt(rig.node.job(7))
    assert rig.jobs.handles[0].cancelled
    assert _sizes(rig).stops == 0


def test_a_closed_utterance_stops_the_partial_run_running_and_its_text_is_not_published() -> None:
    rig = _partial_started()

    def closes() -> None:
        assert not rig.runs.adopt(rig.node.job(7))

    _sizes(rig).during = closes
    rig.jobs.run_all()
    assert _sizes(rig).stops == 1
    assert rig.published.said == []
    assert rig.runs.partials == PartialCounts(started=1, published=0, worker_seconds=TOOK)


def test_a_closing_utterance_unsets_the_partial_timer() -> None:
    rig = _speaking(paused=False)
    rig.runs.utterance_closed()
    rig.clock.advance(1.0)
    assert rig.runs.partials.started == 0


def test_a_cut_at_the_length_limit_starts_the_partials_of_a_new_utterance() -> None:
    rig = _speaking(paused=False)
    rig.clock.advance(0.4)
    rig.runs.utterance_cut(0.4)
    rig.clock.advance(0.49)
    assert rig.runs.partials.started == 0
    rig.clock.advance(0.01)
    assert rig.runs.partials.started == 1


@pytest.mark.parametrize("how", ["drop", "drop_utterance", "stop"])
def test_an_engine_change_disabling_or_stop_cancels_the_speculation(how: str) -> None:
    rig = _speaking()
    rig.runs.speculate()
    getattr(rig.runs, how)()
    assert rig.jobs.handles[0].cancelled


@pytest.mark.parametrize("how, timer_left", [("drop", True), ("drop_utterance", False), ("stop", False)])
def test_an_engine_change_disabling_or_stop_cancels_the_partial_and_only_the_change_leaves_its_timer(
    how: str, timer_left: bool
) -> None:
    rig = _partial_started()
    rig.node.add(4096)
    rig.runs.heard()  # a block: the next partial is due at 1.0 s
    getattr(rig.runs, how)()
    assert rig.jobs.handles[0].cancelled
    rig.clock.advance(0.5)
    assert rig.runs.partials.started == (2 if timer_left else 1)
