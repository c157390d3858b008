"""The background runs: what the recognition worker does for the utterance still being collected.

Two kinds, at most one of each at a time: a speculation (speculation.py: its text may become the
closed utterance's), and a partial result (partials.py): a Stoppable engine's partial run, or an
Incremental engine's partial feed. Closed utterances always come first. The rules:

- a speculation may start once the speaker has paused for ``speculation_gap`` (or a decision on the
  end of speech waits for it), on an engine that can be stopped (one that cannot only on the
  audio up to the end of speech, with a grammar in force), with the worker idle and no
  speculation there, on audio whose text can serve (EndOfTurn.worth_speculating: not the room
  after a cut, nor audio with no speech heard where the end of speech decides); it cancels a
  partial in progress (it may be the final text);
- a partial may start when one is due (``partial_period``), with the worker idle and no speculation
  there, on audio that grew since the last;
- a block cancels the speculation (what it transcribes is no longer the utterance), not the
  partial (its text is still the text so far);
- a closing utterance adopts the speculation on exactly its audio, engine and grammar (its outcome
  is the utterance's, published at once or when it ends), cancels one on other audio, and cancels
  the partial;
- set_language, set_grammar, disabling and stop cancel both;
- when a run ends, or the worker finishes a closed utterance, the next run may start.

A speculation that ends with the utterance still being collected may end the turn early
(``early_pause``; or ``end_of_speech``: the turn rules asked for a decision on a cut, and the speculation
starts at once, on the samples up to it), and its text is a partial too when it is new. In free
speech with a turn-end model (turn_end_model), the model hears the speculation's audio on a thread
of its own while the engine transcribes it (smart_turn.HeardAlongside), and the decision waits for
its verdict only where the text needs it. Every method is called under the node's lock; the jobs
run on the worker and take the lock.
"""

import functools
import logging
import threading
from concurrent.futures import Future
from dataclasses import InitVar, dataclass, field
from typing import Callable, Optional, Protocol

from speech_event.config import SpeechEventConfig
from speech_event.grammar import Grammar
from speech_event.pipeline.publication import TextOrigin
from speech_event.pipeline.recognition_queue import RecognitionJob, RecognitionOutcome
from speech_event.pipeline.worker import Worker
from speech_event.ports import Audio, Clock, Incremental, Recognizer, Stoppable, Transcript
from speech_event.turns.partials import PartialCounts, PartialFeed, PartialRules
from speech_event.turns.smart_turn import HeardAlongside, TurnHeard
from speech_event.turns.speculation import (
    Speculation,
    SpeculationCounts,
    SpeculationRules,
)
from speech_event.turns.turn_taking import RearmingTimer

_LOG = logging.getLogger("speech_event")


@dataclass(frozen=True)
class UtteranceSoFar:
    """The utterance being collected, as it is now."""

    samples: int
    audio: Callable[[], Audio]  # a copy of its samples, taken only when a run starts
    recognizer: Recognizer  # the engine and grammar in force
    grammar: Optional[Grammar]
    origin: TextOrigin  # of a text of it so far
    # With end_of_speech, where the speech so far ends (end_of_turn.py): a speculation is on the
    # samples up to it, at once, whatever the gap. None: the speaker is still speaking, or no
    # decision on the end of speech is made now (off, or not with this engine and grammar).
    cut: Optional[int] = None
    # Whether a speculation on it can serve what the node publishes (EndOfTurn.worth_speculating).
    worth_speculating: bool = True


class Turn(Protocol):
    """What the background runs ask of turn-taking (TurnTaking)."""

    def gap_passed(self) -> bool:
        """Whether the speaker has paused for speculation_gap since the latest block."""
        ...

    def end_early(self) -> None:
        """A speculation found a complete answer: the turn ends after early_pause."""
        ...

    def speculated(self, samples: int, complete: bool) -> None:
        """A speculation on the first ``samples`` of the utterance being collected ended, its text
        complete by itself or not: a decision on the end of speech may wait for it."""
        ...


@dataclass(eq=False)
class BackgroundRuns:
    """Speculations and partial results on the worker: when each starts, is cancelled, adopted or
    dropped (the rules above), each run's job, and what its outcome becomes."""

    config: InitVar[SpeechEventConfig]
    clock: Clock
    lock: threading.Lock
    worker: Worker
    turn: Turn
    # The utterance being collected; None when there is none (or the node is disabled).
    so_far: Callable[[], Optional[UtteranceSoFar]]
    worker_idle: Callable[[], bool]  # no closed utterance is being recognized or waits for it
    # turn_end_model: whether the audio of the utterance so far says the turn is complete (free
    # speech); None: the text alone decides.
    turn_heard: Optional[TurnHeard] = None
    # Whether turn_heard hears with the engine and language in force now (turn_end_model auto: in
    # English with an engine that closes sentences); None: with every one.
    hears_turn_end: Optional[Callable[[], bool]] = None
    speculations: SpeculationCounts = field(init=False)  # how speculation fared
    partials: PartialCounts = field(init=False)  # how partial results fared

    def __post_init__(self, config: SpeechEventConfig) -> None:
        self._speculation = SpeculationRules(config)
        self._partials = PartialRules(config)
        self._partial_timer = RearmingTimer(self.clock, self.lock, self._partials.due, self.partial)
        self.speculations = self._speculation.counts
        self.partials = self._partials.counts
        self._hearing = HeardAlongside(self.turn_heard) if self.turn_heard is not None else None

    # -- what the node tells them -------------------------------------------------------------------

    def more_audio(self, cut: Optional[int]) -> None:
        """A block was taken: the speculation's audio is no longer the utterance, unless it is the
        audio up to ``cut``, where the speech so far ends (end_of_speech)."""
        self._speculation.drop(keep=cut)

    def utterance_started(self, when: float) -> None:
        """An utterance's first block came at ``when``: its first partial is due a period later."""
        self._partials.begin(when)

    def utterance_cut(self, when: float) -> None:
        """A block at ``when`` cut the utterance at the length limit; what is left is a new one."""
        self._speculation.new_utterance()
        self._partials.begin(when)

    def heard(self) -> None:
        """After a block: the partial timer is set for when the next partial is due."""
        if self._partials.on:
            self._partial_timer.arm()

    def utterance_closed(self) -> None:
        """The pause after the utterance has passed: no more partials of it, and the next
        utterance's speculations are compared afresh."""
        self._speculation.new_utterance()
        self._partial_timer.cancel()

    def adopt(self, job: RecognitionJob) -> bool:
        """A closed utterance: whether a speculation on exactly its audio, engine and grammar is its
        recognition (and concludes it); if not, the caller queues it. The partial is cancelled
        either way: the worker is wanted, and no final text waits for a partial."""
        self._partials.drop()
        speculation = self._speculation.adopt(job)
        if speculation is None:
            return False
        if speculation.outcome is None:  # still running: its recognition starts now, as it were
            speculation.watchdog = self.worker.watchdog.watch(job)
        else:  # on the clock's next turn: the worker is idle (see SpeculationRules.adopt)
            self.clock.call_at(
                job.closed_at, functools.partial(self.worker.publication.conclude, job, speculation.outcome)
            )
        return True

    def drop(self) -> None:
        """The engine or the grammar changes: the runs' texts would be the old one's."""
        self._speculation.drop()
        self._partials.drop()

    def drop_utterance(self) -> None:
        """The utterance being collected is thrown away (the node is disabled)."""
        self.drop()
        self._speculation.new_utterance()
        self._partial_timer.cancel()

    def stop(self) -> None:
        """The node stops: cancel both, unset the partial timer, close the turn-end model's thread."""
        self.drop()
        self._partial_timer.cancel()
        if self._hearing is not None:
            self._hearing.close()

    def worker_free(self) -> None:
        """The worker finished a closed utterance: the utterance being collected waited for it."""
        self.speculate()
        self.partial()

    def completed_on(self, samples: int) -> Optional[bool]:
        """Whether the finished speculation on the first ``samples`` is complete by itself (None:
        there is none yet)."""
        return self._speculation.completed_on(samples)

    def running_for(self, job: RecognitionJob) -> bool:
        """Whether ``job``'s recognition is an adopted speculation that runs now."""
        return self._speculation.running_for(job)

    # -- when each starts ---------------------------------------------------------------------------

    def speculate(self) -> None:
        """Speculate on the utterance being collected if its gap has passed and the rules allow it."""
        so_far = self.so_far()
        if so_far is None or not so_far.worth_speculating:
            return
        if so_far.cut is None and not self.turn.gap_passed():
            return
        if so_far.cut is not None:  # one on other audio is worthless: the cut moved since
            self._speculation.drop(keep=so_far.cut)
        # A cut is offered only where the engine and grammar in force decide (EndOfTurn).
        if not self._speculation.may_start(so_far.recognizer, self.worker_idle(), so_far.cut is not None):
            return
        self._partials.drop()  # a speculation comes before a partial: it may be the final text
        audio = so_far.audio()[: so_far.cut]
        speculation = self._speculation.start(audio.size, so_far.recognizer, so_far.grammar)
        speculation.at_last_block = audio.size == so_far.samples
        speculation.hears_turn_end = self._hears_turn_end(so_far.grammar)
        job = functools.partial(self._speculated, speculation, audio, so_far.origin)
        speculation.handle = self.worker.executor.submit(job)

    def partial(self) -> None:
        """Ask for the text of the utterance so far if a partial is due and the worker is idle (no
        closed utterance, no speculation)."""
        so_far, now = self.so_far(), self.clock.now()
        if so_far is None:
            return
        idle = self.worker_idle() and self._speculation.current is None
        if not self._partials.may_start(so_far.recognizer, idle, so_far.samples, now):
            return
        audio, recognizer, submit = so_far.audio(), so_far.recognizer, self.worker.executor.submit
        if isinstance(recognizer, Stoppable):
            run = self._partials.start_run(audio.size, recognizer, so_far.grammar, now)
            run.handle = submit(functools.partial(self._partial_run, run, audio, so_far.origin))
        elif isinstance(recognizer, Incremental):
            feed = self._partials.start_feed(recognizer, so_far.grammar, now)
            job = functools.partial(self._partial_feed, feed, audio[feed.fed :], so_far.origin)
            feed.fed, feed.handle = audio.size, submit(job)

    # -- the jobs, on the worker --------------------------------------------------------------------

    def _running(self, run: Speculation) -> bool:
        """Whether ``run`` runs now: False when it was cancelled before."""
        with self.lock:
            run.running = not run.cancelled
            return run.running

    def _speculated(self, speculation: Speculation, audio: Audio, origin: TextOrigin) -> None:
        """Transcribe the utterance so far; publish it only if it closed as it is."""
        if not self._running(speculation):
            return
        verdict = self._hear_alongside(speculation, audio)
        outcome = self.worker.recognize(audio, speculation.recognizer, speculation.grammar)
        heard = self._heard_complete(speculation, outcome, verdict)
        partial: Optional[Transcript] = None
        with self.lock:
            job = self._speculation.finished(speculation, outcome, heard)
            if job is None and not speculation.cancelled:
                if self._speculation.ends_turn(speculation):
                    self.turn.end_early()
                self.turn.speculated(speculation.samples, speculation.complete)
                if speculation.adopted is None:  # the utterance so far: its text is a partial too
                    partial = self._partials.spoken(speculation.samples, outcome.answer)
        if job is not None:
            self.worker.publication.conclude(job, outcome)
            with self.lock:  # the worker is free: a decision on the end of speech may wait for it
                so_far = self.so_far()
                if so_far is not None and so_far.cut is not None:
                    self.speculate()
        elif partial is not None:
            self.worker.publication.partial(partial, origin)

    def _hears_turn_end(self, grammar: Optional[Grammar]) -> bool:
        """Whether the turn-end model hears a speculation started now (in free speech)."""
        in_force = self.hears_turn_end is None or self.hears_turn_end()
        return self._hearing is not None and grammar is None and in_force

    def _hear_alongside(self, speculation: Speculation, audio: Audio) -> "Optional[Future[bool]]":
        """In free speech with a turn-end model, its verdict on the speculation's audio, asked now,
        while the engine transcribes it (HeardAlongside); None where no verdict can count."""
        if self._hearing is None or not speculation.hears_turn_end:
            return None
        return self._hearing.ask(audio, speculation.at_last_block)

    def _heard_complete(
        self, speculation: Speculation, outcome: RecognitionOutcome, verdict: "Optional[Future[bool]]"
    ) -> bool:
        """Whether the audio says the turn is complete too, where the rules need it (free speech, a
        complete text that is not one of complete_answers), off the lock: a function of the audio
        alone, like the text."""
        if verdict is None:
            return True
        if not self._speculation.needs_the_audio(speculation, outcome):
            verdict.cancel()  # unheard if it has not started: the next one waits for none
            return True
        return verdict.result()

    def _partial_run(self, run: Speculation, audio: Audio, origin: TextOrigin) -> None:
        """A Stoppable engine's text of the utterance so far."""
        if not self._running(run):
            return
        outcome = self.worker.recognize(audio, run.recognizer, run.grammar)
        with self.lock:
            partial = self._partials.finished(run, outcome)
            self.partial()  # more audio came meanwhile
        if partial is not None:
            self.worker.publication.partial(partial, origin)

    def _partial_feed(self, feed: PartialFeed, audio: Audio, origin: TextOrigin) -> None:
        """An Incremental engine fed the new audio of the utterance so far."""
        began = self.worker.stopwatch()
        try:
            answer = feed.feed(audio)
        except (Exception, SystemExit):  # no partial; the final recognition says what failed
            _LOG.debug("a partial result failed", exc_info=True)
            answer = None
        with self.lock:
            partial = self._partials.fed(feed, answer, self.worker.stopwatch() - began)
            self.partial()  # more audio came meanwhile
        if partial is not None:
            self.worker.publication.partial(partial, origin)
