"""The Speech Event node: message in -> validate -> assemble -> resample -> screen -> recognize
(off the callback) -> publish.

Everything it touches comes through its constructor: the transport, the clock, the recognizer and
the executor that runs recognition off the subscriber callback. It reads no clock but the one it is
given (the stopwatch only times recognitions for diagnostics) and keeps no module state, so the
same object runs on the in-memory bus, on a real roscore, and on the robot.

This module is the wiring. The steps live in ``speech_event.pipeline``, the robot's interfaces
around them in ``speech_event.interfaces``, and the rules in modules of their own: when an
utterance ends (``turn_taking``), what the worker does for the utterance still being collected
(``background_runs``: speculations and partial results), the recognition timeout (``watchdog``)
and the periodic checks (``health``). They are called under the node's lock.
"""

import logging
import threading
import time
from typing import Callable, Dict, Optional, Tuple

from speech_event.background_runs import BackgroundRuns, UtteranceSoFar
from speech_event.config import SpeechEventConfig, end_of_speech_chosen
from speech_event.end_of_turn import EndOfTurn
from speech_event.grammar import FREE_SPEECH, Grammar
from speech_event.health import Health
from speech_event.interfaces.action import ACTION_NAME, DISABLED, ListenAction
from speech_event.interfaces.diagnostics import (
    DISCARDED_AFTER_SPEECH,
    DISCARDED_WHILE_DISABLED,
    NodeState,
    NodeStatistics,
)
from speech_event.interfaces.language_engines import EngineBuilder, LanguageEngines
from speech_event.interfaces.services import (
    SET_ENABLED_SERVICE,
    SET_GRAMMAR_SERVICE,
    SET_LANGUAGE_SERVICE,
    RuntimeControl,
    starting_grammar,
)
from speech_event.interfaces.storage import store_for
from speech_event.messages import RECOGNISE_SPEECH, SET_ENABLED, SET_GRAMMAR, SET_LANGUAGE, Float32MultiArray
from speech_event.partials import PartialCounts
from speech_event.pipeline.assembly import UtteranceAssembler
from speech_event.pipeline.closed_utterances import ClosedUtterances
from speech_event.pipeline.publication import Publication, TextOrigin
from speech_event.pipeline.recognition import Recognition
from speech_event.pipeline.recognition_queue import RecognitionJob, RecognitionQueue
from speech_event.pipeline.rejections import RejectionLog
from speech_event.pipeline.screen import SpeechScreen, speech_screen_for
from speech_event.pipeline.smart_turn import turn_heard_for
from speech_event.pipeline.validate import Rejection, validate_signal
from speech_event.pipeline.worker import Worker
from speech_event.ports import (
    Audio,
    Clock,
    Executor,
    PublisherStatus,
    Received,
    Recognizer,
    Stoppable,
    Transport,
    engine_name,
)
from speech_event.speculation import SpeculationCounts, decides_at_end_of_speech
from speech_event.topics import SIGNAL_TOPIC, SOUND_DETECTION_DOWN
from speech_event.turn_taking import TurnTaking
from speech_event.watchdog import Watchdog

_LOG = logging.getLogger("speech_event")


class SpeechEventNode:
    """The node: wires the pipeline, the rules and the robot's interfaces to the injected ports."""

    def __init__(
        self,
        config: SpeechEventConfig,
        transport: Transport,
        clock: Clock,
        recognizer: Recognizer,
        executor: Executor,
        build_engine: Optional[EngineBuilder] = None,
        screen: Optional[SpeechScreen] = None,
        stopwatch: Callable[[], float] = time.perf_counter,
    ) -> None:
        """``recognizer`` transcribes ``config.language``; ``build_engine`` builds another language's
        engine when set_language asks for it (without it, only the configured language is served).
        ``screen`` decides what is not speech (default: built from the configuration). ConfigError
        when the configured grammar cannot be read or the engine cannot take it."""
        self._config = config
        self._transport = transport
        self._clock = clock
        screen = screen or speech_screen_for(config)
        self._max_samples = int(config.max_message_length * config.sample_rate)
        self._assembler = UtteranceAssembler(
            config.sample_rate, config.max_utterance_length, screen.non_speech
        )
        self._rejections = RejectionLog(clock.now, SIGNAL_TOPIC)
        self._store = store_for(config)
        self._statistics = NodeStatistics()
        self._action = ListenAction(clock, self._refusal)
        self._publication = Publication(config, self._statistics, self._action, self._store, clock.now)
        self._control = RuntimeControl(
            LanguageEngines(config.language, recognizer, build_engine),
            self._in_force,
            self.set_enabled,
            self._use_engine,
            self._use_grammar,
        )
        # The subscriber callback, the clock's timers, the service handlers and the recognition
        # worker may each run on their own thread (rospy); this lock guards the assembler, the
        # rules' state, the engine and grammar in use and the enabled flag.
        self._lock = threading.Lock()
        self._language = config.language
        self._recognizer = recognizer
        self._grammar = starting_grammar(config, recognizer)
        self._enabled = True
        self._collecting_since: Optional[float] = None  # when the utterance being collected started
        chosen = end_of_speech_chosen(config)
        turn_heard = turn_heard_for(config)

        def deciding() -> bool:  # whether the end of speech decides with the engine and grammar in use
            return decides_at_end_of_speech(self._recognizer, self._grammar, chosen, turn_heard is not None)

        self._end = EndOfTurn(config, deciding, lambda: not isinstance(self._recognizer, Stoppable))
        self._turn = TurnTaking(
            config,
            clock,
            self._lock,
            self._close_utterance,
            self._gap_passed,
            self._silence_passed,
            self._speculated,
            deciding,
        )
        self._watchdog = Watchdog(clock, self._lock, config.recognition_timeout, self._still_running)
        recognition = Recognition(config.sample_rate, screen, stopwatch)
        worker = Worker(executor, recognition, stopwatch, self._publication, self._watchdog)
        self._queue = RecognitionQueue(config.max_backlog)
        self._closed = ClosedUtterances(
            self._queue, self._lock, worker, lambda: self._background.worker_free()
        )
        self._background = BackgroundRuns(
            config, clock, self._lock, worker, self._turn, self._so_far, self._closed.idle, turn_heard
        )
        self.speculations: SpeculationCounts = self._background.speculations  # how speculation fared
        self.partials: PartialCounts = self._background.partials  # how partial results fared
        self._health = Health(
            config, transport, clock, self._statistics, self._state, self._sound_detection_down
        )
        self._utterances = 0
        self._started_at = 0.0

    @property
    def rejection_counts(self) -> Dict[str, int]:
        """Messages rejected so far, by reason."""
        with self._lock:
            return {reason.value: count for reason, count in self._rejections.counts.items()}

    @property
    def pending_samples(self) -> int:
        """Samples of the utterance being collected, not yet handed to recognition."""
        with self._lock:
            return self._assembler.pending_samples

    @property
    def queued_speech_seconds(self) -> float:
        """Seconds of speech waiting for recognition (bounded by max_backlog)."""
        return self._queue.seconds

    @property
    def dropped_utterances(self) -> int:
        """Utterances dropped unrecognized to keep within max_backlog."""
        return self._queue.dropped

    @property
    def started_at(self) -> float:
        """When start() ran, on the node's clock: health checks come every period from here."""
        return self._started_at

    @property
    def language(self) -> str:
        """The language transcribed now."""
        with self._lock:
            return self._language

    @property
    def grammar(self) -> Optional[Grammar]:
        """The grammar in force now (set_grammar); None for free speech."""
        with self._lock:
            return self._grammar

    @property
    def enabled(self) -> bool:
        """Whether the node transcribes now (set_enabled)."""
        with self._lock:
            return self._enabled

    def start(self) -> None:
        """Advertise, subscribe, serve, and start the health checks."""
        self._publication.start(self._transport)
        self._transport.subscribe(SIGNAL_TOPIC, Float32MultiArray, self.on_signal)
        self._transport.serve(SET_ENABLED_SERVICE, SET_ENABLED, self._control.on_set_enabled)
        self._transport.serve(SET_LANGUAGE_SERVICE, SET_LANGUAGE, self._control.on_set_language)
        self._transport.serve(SET_GRAMMAR_SERVICE, SET_GRAMMAR, self._control.on_set_grammar)
        self._transport.serve_action(
            ACTION_NAME, RECOGNISE_SPEECH, self._action.on_goal, self._action.on_cancel
        )
        self._started_at = self._clock.now()
        self._health.start(self._started_at)
        _LOG.info("speechEvent started: %s", self._config)

    def stop(self) -> None:
        """Stop the timers; an utterance still being collected is not transcribed."""
        self._health.stop()
        with self._lock:
            self._turn.stop()
            self._background.stop()
            self._end.dropped()

    def flush_storage(self) -> None:
        """Wait until every utterance transcribed so far is stored (when storing is on)."""
        if self._store is not None:
            self._store.flush()

    # -- message in -> validate -> assemble ---------------------------------------------------------

    def on_signal(self, message: object) -> None:
        """The subscriber callback: cheap, never blocks on recognition, never raises."""
        arrival = message.received_at if isinstance(message, Received) else self._clock.now()
        try:
            self._take(message, arrival)
        except Exception:  # validation names every bad message; this is the last line of defence
            _LOG.exception("unexpected failure handling a message on %s; the node goes on", SIGNAL_TOPIC)

    def _take(self, message: object, arrival: float) -> None:
        signal = validate_signal(message, self._max_samples)
        with self._lock:  # rospy may call back from two connections at once (a restart overlapping)
            if not self._enabled:  # the robot is speaking: its own voice is not to be transcribed
                self._statistics.ignored_while_disabled()
                return
            if isinstance(signal, Rejection):
                self._rejections.record(signal)
                return
            if signal.clipped:
                self._rejections.record_clipped(signal.clipped)
            self._arrived(signal.samples, arrival)

    def _arrived(self, samples: Audio, arrival: float) -> None:
        """Under the lock: a block that arrived at ``arrival``, taken now or held for a decision."""
        # First: a speculation on the utterance it ends still counts, and a decision on the end of
        # speech that the gap before it asks for is made before it is taken.
        self._turn.end_pause_if_over(arrival)
        if self._end.deciding is not None:
            self._end.hold(samples, arrival)
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
            self._end.cut_at_length(self._assembler.peek())
        else:
            self._end.heard(samples)
        self._background.more_audio(self._end.speculation_cut())
        self._turn.heard(arrival)
        self._background.heard()
        cut = self._end.heard_end()
        if cut is not None:
            self._decide(cut)
        elif self._end.speculation_cut() is not None:
            self._background.speculate()  # the speech may have ended: its text is ready sooner

    def _gap_passed(self) -> None:
        """Under the lock: no block came for speculation_gap."""
        self._background.speculate()

    def _silence_passed(self) -> None:
        """Under the lock: no block came for end_of_speech: the end of speech (the robot's gate)."""
        self._decide(self._end.gap_end())
        self._background.speculate()

    def _decide(self, cut: Optional[int]) -> None:
        """Under the lock: a speculation on the utterance up to ``cut`` (offered only where the
        engine and grammar in force decide) decides whether the turn ends there."""
        if cut is None or not self._enabled:
            return
        self._end.decide(cut)
        complete = self._background.completed_on(cut)
        if complete is not None:  # the speculation on that audio has finished already
            self._decided(complete)
        else:
            self._background.speculate()

    def _speculated(self, samples: int, complete: bool) -> None:
        """Under the lock: a speculation on the utterance being collected ended; if it is the
        pending decision, the turn ends at its cut when its text is complete."""
        if self._end.deciding == samples:
            self._decided(complete)

    def _decided(self, complete: bool) -> None:
        """Under the lock: the pending decision is made; then the blocks held meanwhile are taken."""
        cut, close_waits = self._end.deciding, self._end.close_waits
        held = self._end.decided()
        if complete and cut is not None:
            audio = self._assembler.close()
            self._background.utterance_closed()
            self._turn.drop_turn()
            if audio is not None:
                self._submit(audio[:cut], False, self._turn.last_arrival)
            self._end.closed(at_cut=True)
            if audio is not None and audio.size > cut:
                # What follows the cut begins the next utterance: mostly the room after the
                # speech, which is dropped unless speech follows, but a quiet word after a pause
                # ("go somewhere ... and do something") is no speech to the detector until then.
                self._arrived(audio[cut:], self._turn.last_arrival)
        if close_waits and not complete:  # the pause ended meanwhile: a block held since ends it
            self._turn.pause_again()
        for block in held:
            self._arrived(block.samples, block.arrival)

    def _undecided(self) -> None:
        """Under the lock: the speculation a decision waited for was dropped; the turn goes on."""
        if self._end.deciding is not None:
            self._decided(False)

    def _close_utterance(self) -> None:
        """Under the lock: the pause after the utterance being collected has passed."""
        if self._end.deciding is not None:  # the decision may end it elsewhere: it comes first
            self._end.close_waits = True
            return
        self._background.utterance_closed()
        utterance = self._assembler.close()
        if utterance is not None and not self._end.worth_transcribing():
            self._statistics.discarded(DISCARDED_AFTER_SPEECH)
            self._action.utterance_dropped()
            self._collecting_since = None
        elif utterance is not None:
            self._submit(utterance, False, self._turn.last_arrival)
        self._end.closed(at_cut=False)

    def _so_far(self) -> Optional[UtteranceSoFar]:
        """Under the lock: the utterance being collected, None when there is none (or disabled)."""
        pending, last = self._assembler.pending_samples, self._turn.last_arrival
        if not self._enabled or pending == 0:
            return None
        first = self._collecting_since if self._collecting_since is not None else last
        origin = TextOrigin(
            self._language, engine_name(self._recognizer), first, last, self._grammar is not None
        )
        return UtteranceSoFar(
            pending,
            self._assembler.peek,
            self._recognizer,
            self._grammar,
            origin,
            self._end.speculation_cut(paused=self._turn.gap_passed()),
        )

    def _submit(self, audio: Audio, more_follows: bool, last_block_at: float) -> None:
        """Hand a closed utterance to recognition with the engine in use now (under the lock)."""
        self._utterances += 1
        number, closed_at, recognizer = self._utterances, self._clock.now(), self._recognizer
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
            recognizer,
            self._language,
            seconds,
            self._grammar,
        )
        if not self._background.adopt(job):
            self._closed.put(job)

    def _still_running(self, job: RecognitionJob) -> bool:
        """Under the lock: whether ``job``'s recognition runs now (on the worker, or speculated)."""
        return self._closed.running is job or self._background.running_for(job)

    # -- runtime control --------------------------------------------------------------------------

    def set_enabled(self, enabled: bool) -> None:
        """Disabled, arriving blocks are thrown away and the utterance being collected is dropped (it
        is the robot's own voice); enabled again, the node starts clean. Health checks go on, and
        recognitions already handed over still publish."""
        with self._lock:
            self._end_turn_if_over()  # an utterance already over is no robot's voice
            changed = enabled != self._enabled
            self._enabled = enabled
            if not enabled:
                self._background.drop_utterance()
                self._turn.drop_turn()
                self._end.dropped()
                if self._assembler.close() is not None:
                    self._statistics.discarded(DISCARDED_WHILE_DISABLED)
                    self._action.utterance_dropped()
                self._collecting_since = None
        if changed:
            _LOG.info("speechEvent %s", "enabled" if enabled else "disabled")
        if not enabled:
            self._action.disabled()

    def _use_engine(self, language: str, recognizer: Recognizer) -> None:
        with self._lock:  # utterances closed before this finish with the old engine
            self._end_turn_if_over()
            self._background.drop()
            self._undecided()
            self._language, self._recognizer = language, recognizer
        _LOG.info("speechEvent transcribes %s now", language)

    def _use_grammar(self, grammar: Optional[Grammar]) -> None:
        with self._lock:  # utterances closed before this finish with the old grammar
            self._end_turn_if_over()
            self._background.drop()
            self._undecided()
            self._grammar = grammar
        _LOG.info("speechEvent grammar: %s", FREE_SPEECH if grammar is None else grammar.source)

    def _end_turn_if_over(self) -> None:
        """Under the lock, before a call changes the engine, the grammar or the enabled flag: an
        utterance whose pause is over by now ends first, with what was in force while it was said.
        Also while a decision on its end of speech is still pending, which a slow engine or a busy
        machine leaves pending past the pause: the decision is dropped and the whole utterance
        transcribed, so how long the engine takes never decides what a call applies to."""
        now = self._clock.now()
        self._turn.end_pause_if_over(now)
        if self._end.close_waits:
            self._background.drop()
            self._undecided()
            self._turn.end_pause_if_over(now)

    def _in_force(self) -> Tuple[str, Recognizer, Optional[Grammar]]:
        """The language, engine and grammar in use now."""
        with self._lock:
            return self._language, self._recognizer, self._grammar

    def _refusal(self) -> Optional[str]:
        """Why an action goal cannot listen now, or None."""
        if not self.enabled:
            return DISABLED
        if not self._transport.publisher_status(SIGNAL_TOPIC).up:
            return SOUND_DETECTION_DOWN
        return None

    # -- health and diagnostics -------------------------------------------------------------------

    def _sound_detection_down(self) -> None:
        language, engine = self._in_force()[:2]
        self._publication.publish_error(SOUND_DETECTION_DOWN, language, engine_name(engine))
        self._action.sound_detection_down()

    def _state(self, sound_detection: PublisherStatus) -> NodeState:
        with self._lock:
            return NodeState(
                engine=engine_name(self._recognizer),
                language=self._language,
                grammar="" if self._grammar is None else self._grammar.source,
                enabled=self._enabled,
                sound_detection=sound_detection,
                rejected={reason.value: count for reason, count in self._rejections.counts.items()},
                clipped=self._rejections.clipped,
                timed_out=self._watchdog.timed_out,
                utterances=self._utterances,
                queued_seconds=self._queue.seconds,
                dropped=self._queue.dropped,
                partials_published=self.partials.published,
                partial_seconds=self.partials.worker_seconds,
            )
