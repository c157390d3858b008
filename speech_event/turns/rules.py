"""The turn rules on the utterance being collected, behind one entry: the node hands each block it
took to ``take``, and tells of changes (``engine_or_grammar_changes``; ``end_turn_if_over`` and
``drop_utterance`` for set_enabled; ``stop``); the timers call back in here. Everything else stays inside:

- the blocks go to the utterance assembler, and each utterance that closes goes to recognition
  (adopted by the speculation on exactly its audio, or queued for the worker);
- the pause after the latest block ends the utterance (turn_taking.py), or a decision on the end of
  speech ends the turn where the speech ended (end_of_turn.py, with speech_end.py), while the
  blocks that arrive meanwhile are held;
- the worker speculates on the utterance so far and runs partial results when it is idle
  (background_runs.py, with speculation.py and partials.py).

Every method is called under the node's lock.
"""

import threading
from dataclasses import dataclass
from typing import ContextManager, Optional

from speech_event.config import SpeechEventConfig, end_of_speech_chosen
from speech_event.grammar import Grammar
from speech_event.interfaces.action import ListenAction
from speech_event.interfaces.diagnostics import (
    DISCARDED_AFTER_SPEECH,
    DISCARDED_WHILE_DISABLED,
    NodeStatistics,
)
from speech_event.pipeline.assembly import UtteranceAssembler
from speech_event.pipeline.closed_utterances import ClosedUtterances
from speech_event.pipeline.publication import TextOrigin
from speech_event.pipeline.recognition_queue import RecognitionJob, RecognitionQueue
from speech_event.pipeline.worker import Worker
from speech_event.ports import Audio, Clock, Recognizer, Stoppable, engine_name
from speech_event.turns.background_runs import BackgroundRuns, UtteranceSoFar
from speech_event.turns.end_of_turn import EndOfTurn
from speech_event.turns.partials import PartialCounts
from speech_event.turns.smart_turn import TurnEnd
from speech_event.turns.speculation import SpeculationCounts, decides_at_end_of_speech
from speech_event.turns.turn_taking import TurnTaking


@dataclass
class InForce:
    """What the node transcribes with now (set_language, set_grammar, set_enabled): the node
    writes it, the rules read it, both under the node's lock."""

    language: str
    recognizer: Recognizer
    grammar: Optional[Grammar]  # None: free speech
    enabled: bool = True


class TurnRules:
    """The utterance being collected: when it ends, and what the worker does for it meanwhile."""

    def __init__(
        self,
        config: SpeechEventConfig,
        clock: Clock,
        lock: threading.Lock,
        in_force: InForce,
        assembler: UtteranceAssembler,
        worker: Worker,
        queue: RecognitionQueue,
        action: ListenAction,
        statistics: NodeStatistics,
        turn_end: Optional[TurnEnd] = None,
    ) -> None:
        """``queue``: where closed utterances wait for ``worker``; ``action`` and ``statistics``
        hear of each utterance started, closed and dropped; ``turn_end``: the turn-end model
        (turn_end_model), None for the text alone."""
        self._config = config
        self._clock = clock
        self._in_force = in_force
        self._assembler = assembler
        self._action = action
        self._statistics = statistics
        self._collecting_since: Optional[float] = None  # when the utterance being collected started
        self.utterances = 0  # closed and handed to recognition so far
        chosen = end_of_speech_chosen(config)

        def hears_turn_end() -> bool:  # whether the turn-end model hears with the engine in use
            return turn_end is not None and turn_end.hears(in_force.language, in_force.recognizer)

        def deciding() -> bool:  # whether the end of speech decides with the engine and grammar in use
            return decides_at_end_of_speech(in_force.recognizer, in_force.grammar, chosen, hears_turn_end())

        self._end_of_speech = EndOfTurn(
            config, decides=deciding, decides_once=lambda: not isinstance(in_force.recognizer, Stoppable)
        )
        self._pauses = TurnTaking(
            config,
            clock,
            lock,
            on_pause_end=self._pause_passed,
            on_gap=self._gap_passed,
            on_silence=self._silence_passed,
            on_speculated=self._speculated,
            deciding=deciding,
        )
        # Step 3 of the pipeline, here since what the worker does for the utterance being collected
        # waits for it; each closed utterance it finishes lets the background runs go on (a lambda:
        # they are made next).
        self._closed = ClosedUtterances(queue, lock, worker, lambda: self._background.worker_free())
        self._background = BackgroundRuns(
            config,
            clock,
            lock,
            worker,
            turn=self._pauses,
            so_far=self._so_far,
            worker_idle=self._closed.idle,
            turn_heard=turn_end.heard if turn_end is not None else None,
            hears_turn_end=hears_turn_end,
        )
        self.speculations: SpeculationCounts = self._background.speculations
        self.partials: PartialCounts = self._background.partials

    @property
    def pending_samples(self) -> int:
        """Samples of the utterance being collected, not yet handed to recognition."""
        return self._assembler.pending_samples

    def still_running(self, job: RecognitionJob) -> bool:
        """Whether ``job``'s recognition runs now (on the worker, or as an adopted speculation)."""
        return self._closed.running is job or self._background.running_for(job)

    # -- what the node tells ------------------------------------------------------------------------

    def arriving(self, at: float) -> ContextManager[None]:
        """While a block that arrived at ``at`` waits for the node's lock and is taken: no timer
        hears a pause before it (turn_taking.ArrivingBlocks)."""
        return self._pauses.waiting_blocks.arriving(at)

    def taken(self, when: float) -> None:
        """The callback that took a block returns at ``when`` (TurnTaking.taken). Not while a
        decision holds the blocks: those are taken later, by their arrivals."""
        if self._end_of_speech.deciding is None:
            self._pauses.taken(when)

    def take(self, samples: Audio, arrival: float) -> None:
        """A block that arrived at ``arrival``, taken now or held for a decision."""
        # First: a speculation on the utterance it ends still counts, and a decision on the end of
        # speech that the gap before it asks for is made before it is taken.
        self._pauses.end_pause_if_over(arrival)
        if self._end_of_speech.deciding is not None:
            self._end_of_speech.hold(samples, arrival)
            return
        if self._assembler.pending_samples == 0:
            self._collecting_since = arrival
            self._action.utterance_started(arrival)
            self._background.utterance_started(arrival)
        completed = self._assembler.add(samples)
        for index, utterance in enumerate(completed):
            # Cut at the length limit: the speech goes on in the next utterance.
            more_follows = index < len(completed) - 1 or self._assembler.pending_samples > 0
            self._submit(utterance, more_follows, arrival)
        if completed:
            self._background.utterance_cut(arrival)
            self._end_of_speech.cut_at_length(self._assembler.peek())
        else:
            self._end_of_speech.heard(samples)
        self._background.more_audio(self._end_of_speech.speculation_cut())
        self._pauses.heard(arrival)
        self._background.heard()
        cut = self._end_of_speech.heard_end()
        if cut is not None:
            self._decide(cut)
        elif self._end_of_speech.speculation_cut() is not None:
            self._background.speculate()  # the speech may have ended: its text is ready sooner

    def end_turn_if_over(self) -> None:
        """Before a call changes the engine, the grammar or the enabled flag: an utterance whose
        pause is over by now ends first, with what was in force while it was said. Also while a
        decision on its end of speech is still pending, which a slow engine or a busy machine
        leaves pending past the pause: the decision is dropped and the whole utterance
        transcribed, so how long the engine takes never decides what a call applies to."""
        now = self._clock.now()
        self._pauses.end_pause_if_over(now)
        if self._end_of_speech.close_waits:
            self._background.drop()
            self._undecided()
            self._pauses.end_pause_if_over(now)

    def engine_or_grammar_changes(self) -> None:
        """Before the engine or the grammar changes: an utterance already over ends first
        (end_turn_if_over); the background runs on the utterance so far used the old engine or
        grammar, so they are dropped, with any decision waiting on one."""
        self.end_turn_if_over()
        self._background.drop()
        self._undecided()

    def drop_utterance(self) -> None:
        """The node is disabled: the utterance being collected is the robot's own voice."""
        self._background.drop_utterance()
        self._pauses.drop_turn()
        self._end_of_speech.dropped()
        if self._assembler.close() is not None:
            self._statistics.discarded(DISCARDED_WHILE_DISABLED)
            self._action.utterance_dropped()
        self._collecting_since = None

    def stop(self) -> None:
        """The node stops: the timers are unset; the utterance being collected is not transcribed."""
        self._pauses.stop()
        self._background.stop()
        self._end_of_speech.dropped()

    # -- the timers and the worker --------------------------------------------------------------------

    def _gap_passed(self) -> None:
        """No block came for speculation_gap."""
        self._background.speculate()

    def _silence_passed(self) -> None:
        """No block came for end_of_speech: the end of speech (the robot's gate)."""
        self._decide(self._end_of_speech.gap_end())
        self._background.speculate()

    def _decide(self, cut: Optional[int]) -> None:
        """A speculation on the utterance up to ``cut`` (offered only where the engine and grammar
        in force decide) decides whether the turn ends there."""
        if cut is None or not self._in_force.enabled:
            return
        self._end_of_speech.decide(cut)
        complete = self._background.completed_on(cut)
        if complete is not None:  # the speculation on that audio has finished already
            self._decided(complete)
        else:
            self._background.speculate()

    def _speculated(self, samples: int, complete: bool) -> None:
        """A speculation on the utterance being collected ended; if it is the pending decision,
        the turn ends at its cut when its text is complete."""
        if self._end_of_speech.deciding == samples:
            self._decided(complete)

    def _decided(self, complete: bool) -> None:
        """The pending decision is made; then the blocks held meanwhile are taken."""
        cut, close_waits = self._end_of_speech.deciding, self._end_of_speech.close_waits
        held = self._end_of_speech.decided()
        if complete and cut is not None:
            audio = self._assembler.close()
            self._background.utterance_closed()
            self._pauses.drop_turn()
            if audio is not None:
                self._submit(audio[:cut], False, self._pauses.last_arrival)
            self._end_of_speech.closed(at_cut=True)
            if audio is not None and audio.size > cut:
                # What follows the cut begins the next utterance: mostly the room after the
                # speech, which is dropped unless speech follows, but a quiet word after a pause
                # ("go somewhere ... and do something") is no speech to the detector until then.
                self.take(audio[cut:], self._pauses.last_arrival)
        if close_waits and not complete:  # the pause ended meanwhile: a block held since ends it
            self._pauses.pause_again()
        for block in held:
            self.take(block.samples, block.arrival)

    def _undecided(self) -> None:
        """The speculation a decision waited for was dropped; the turn goes on."""
        if self._end_of_speech.deciding is not None:
            self._decided(False)

    def _pause_passed(self) -> None:
        """The pause after the utterance being collected has passed."""
        if self._end_of_speech.deciding is not None:  # the decision may end it elsewhere: it comes first
            self._end_of_speech.close_waits = True
            return
        self._background.utterance_closed()
        utterance = self._assembler.close()
        if utterance is not None and not self._end_of_speech.worth_transcribing():
            self._statistics.discarded(DISCARDED_AFTER_SPEECH)
            self._action.utterance_dropped()
            self._collecting_since = None
        elif utterance is not None:
            self._submit(utterance, False, self._pauses.last_arrival)
        self._end_of_speech.closed(at_cut=False)

    def _so_far(self) -> Optional[UtteranceSoFar]:
        """The utterance being collected, None when there is none (or the node is disabled)."""
        pending, last, in_force = self._assembler.pending_samples, self._pauses.last_arrival, self._in_force
        if not in_force.enabled or pending == 0:
            return None
        first = self._collecting_since if self._collecting_since is not None else last
        origin = TextOrigin(
            in_force.language, engine_name(in_force.recognizer), first, last, in_force.grammar is not None
        )
        return UtteranceSoFar(
            pending,
            self._assembler.peek,
            in_force.recognizer,
            in_force.grammar,
            origin,
            self._end_of_speech.speculation_cut(paused=self._pauses.gap_passed()),
            self._end_of_speech.worth_speculating(),
        )

    def _submit(self, audio: Audio, more_follows: bool, last_block_at: float) -> None:
        """Hand a closed utterance to recognition with the engine and grammar in force now."""
        self.utterances += 1
        number, closed_at = self.utterances, self._clock.now()
        started_at = self._collecting_since if self._collecting_since is not None else closed_at
        if not more_follows:
            self._collecting_since = None
        seconds = audio.size / self._config.sample_rate
        self._statistics.queued(seconds)
        self._action.utterance_closed(number, started_at, more_follows)
        job = RecognitionJob(
            number,
            started_at,
            closed_at,
            last_block_at,
            audio,
            self._in_force.recognizer,
            self._in_force.language,
            seconds,
            self._in_force.grammar,
        )
        if not self._background.adopt(job):
            self._closed.put(job)
