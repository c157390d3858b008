"""The Speech Event node: message in -> validate -> turn rules (assemble, end of turn) -> queue ->
resample -> screen -> recognize (off the callback) -> publish.

Everything it touches comes through its constructor: the transport, the clock, the recognizer and
the executor that runs recognition off the subscriber callback. Its rules read no clock but the one
it is given (the stopwatch only times recognitions for diagnostics, and the store rate-limits its
warnings on the monotonic clock) and it keeps no module state, so the same object runs on the
in-memory bus, on a real roscore, and on the robot.

This module is the wiring. The steps live in ``speech_event.pipeline``, the robot's interfaces
around them (services, action, diagnostics, the periodic health checks) in
``speech_event.interfaces``, and the rules on the utterance being collected (when it ends, what
the worker does for it meanwhile) in ``speech_event.turns``, whose ``TurnRules`` takes each block
the node accepts. The turn rules, the services and the health checks are called under the node's
lock; recognition and publication run on the worker without it.
"""

import logging
import threading
import time
from contextlib import nullcontext
from typing import Callable, Dict, Optional, Tuple

from speech_event.config import SpeechEventConfig
from speech_event.grammar import FREE_SPEECH, Grammar
from speech_event.interfaces.action import ACTION_NAME, DISABLED, ListenAction
from speech_event.interfaces.diagnostics import NodeState, NodeStatistics
from speech_event.interfaces.health import Health
from speech_event.interfaces.language_engines import LanguageEngines
from speech_event.interfaces.services import (
    SET_ENABLED_SERVICE,
    SET_GRAMMAR_SERVICE,
    SET_LANGUAGE_SERVICE,
    RuntimeControl,
    starting_grammar,
)
from speech_event.messages import RECOGNISE_SPEECH, SET_ENABLED, SET_GRAMMAR, SET_LANGUAGE, Float32MultiArray
from speech_event.pipeline.assembly import UtteranceAssembler
from speech_event.pipeline.publication import Publication
from speech_event.pipeline.recognition import Recognition
from speech_event.pipeline.recognition_queue import RecognitionQueue
from speech_event.pipeline.rejections import RejectionLog
from speech_event.pipeline.screen import Discard, SpeechScreen, speech_screen_for
from speech_event.pipeline.storage import store_for
from speech_event.pipeline.validate import Rejection, validate_signal
from speech_event.pipeline.watchdog import Watchdog
from speech_event.pipeline.worker import Worker
from speech_event.ports import (
    Clock,
    EngineBuilder,
    Executor,
    PublisherStatus,
    Received,
    Recognizer,
    Transport,
    engine_name,
)
from speech_event.topics import SIGNAL_TOPIC, SOUND_DETECTION_DOWN
from speech_event.turns.partials import PartialCounts
from speech_event.turns.rules import InForce, TurnRules
from speech_event.turns.smart_turn import turn_end_for
from speech_event.turns.speculation import SpeculationCounts

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
        self._rejections = RejectionLog(clock.now, SIGNAL_TOPIC)
        self._store = store_for(config)
        self._statistics = NodeStatistics()
        self._action = ListenAction(clock, self._refusal)
        self._publication = Publication(config, self._statistics, self._action, self._store, clock.now)
        self._control = RuntimeControl(
            LanguageEngines(config.language, recognizer, build_engine),
            current=self._engine_and_grammar,
            set_enabled=self.set_enabled,
            use_engine=self._use_engine,
            use_grammar=self._use_grammar,
        )
        # The subscriber callback, the clock's timers, the service handlers and the recognition
        # worker may each run on their own thread (rospy); this lock guards the rules' state (the
        # utterance being collected) and what is in force.
        self._lock = threading.Lock()
        self._in_force = InForce(config.language, recognizer, starting_grammar(config, recognizer))
        # A lambda: the turn rules, which know what runs on the worker, are made below.
        self._watchdog = Watchdog(
            clock, self._lock, config.recognition_timeout, lambda job: self._turns.still_running(job)
        )
        recognition = Recognition(config.sample_rate, screen, stopwatch)
        worker = Worker(executor, recognition, stopwatch, self._publication, self._watchdog)
        self._queue = RecognitionQueue(config.max_backlog)
        self._turn_end = turn_end_for(config)
        if self._turn_end is not None:
            self._turn_end.prepare(config.language, recognizer)
        self._turns = TurnRules(
            config,
            clock,
            self._lock,
            self._in_force,
            UtteranceAssembler(config.sample_rate, config.max_utterance_length, screen.non_speech),
            worker,
            self._queue,
            self._action,
            self._statistics,
            self._turn_end,
        )
        self.speculations: SpeculationCounts = self._turns.speculations  # how speculation fared
        self.partials: PartialCounts = self._turns.partials  # how partial results fared
        discards = [reason.value for reason in Discard]
        self._health = Health(
            config, transport, clock, self._statistics, self._state, self._sound_detection_down, discards
        )
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
            return self._turns.pending_samples

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
            return self._in_force.language

    @property
    def grammar(self) -> Optional[Grammar]:
        """The grammar in force now (set_grammar); None for free speech."""
        with self._lock:
            return self._in_force.grammar

    @property
    def enabled(self) -> bool:
        """Whether the node transcribes now (set_enabled)."""
        with self._lock:
            return self._in_force.enabled

    def start(self) -> None:
        """Advertise, start the health checks, subscribe and serve.

        The start time is read, and /diagnostics advertised, before the node listens: a replay
        plays once the node listens, so no block comes before the time the checks count from. Read
        last, on a busy machine the action server took long enough to set up that the clock had
        moved on by 'hello', and the checks came 0.43 s after the replay's (outage_crash on ROS)."""
        self._started_at = self._clock.now()
        self._publication.start(self._transport)
        self._health.start(self._started_at)
        self._transport.subscribe(SIGNAL_TOPIC, Float32MultiArray, self.on_signal)
        self._transport.serve(SET_ENABLED_SERVICE, SET_ENABLED, self._control.on_set_enabled)
        self._transport.serve(SET_LANGUAGE_SERVICE, SET_LANGUAGE, self._control.on_set_language)
        self._transport.serve(SET_GRAMMAR_SERVICE, SET_GRAMMAR, self._control.on_set_grammar)
        self._transport.serve_action(
            ACTION_NAME, RECOGNISE_SPEECH, self._action.on_goal, self._action.on_cancel
        )
        _LOG.info("speechEvent started: %s", self._config)

    def stop(self) -> None:
        """Stop the timers; an utterance still being collected is not transcribed."""
        self._health.stop()
        with self._lock:
            self._turns.stop()

    def flush_storage(self) -> None:
        """Wait until every utterance transcribed so far is stored (when storing is on)."""
        if self._store is not None:
            self._store.flush()

    # -- message in -> validate -> turn rules -------------------------------------------------------

    def on_signal(self, message: object) -> None:
        """The subscriber callback: cheap, never blocks on recognition, never raises."""
        # stamped by its transport as read (rospy), or arriving now, in the publisher's thread
        stamp = message.received_at if isinstance(message, Received) else None
        try:
            self._take(message, self._clock.now() if stamp is None else stamp, stamp is not None)
        except Exception:  # validation names every bad message; this is the last line of defence
            _LOG.exception("unexpected failure handling a message on %s; the node goes on", SIGNAL_TOPIC)

    def _take(self, message: object, arrival: float, stamped: bool) -> None:
        signal = validate_signal(message, self._max_samples)
        # audio counts as arrived while it waits for the lock (a rejection is no audio)
        arriving = nullcontext() if isinstance(signal, Rejection) else self._turns.arriving(arrival)
        with arriving, self._lock:  # rospy may call back from two connections at once (a restart overlapping)
            if not self._in_force.enabled:  # the robot is speaking: its own voice is not to be transcribed
                self._statistics.ignored_while_disabled()
                return
            if isinstance(signal, Rejection):
                self._rejections.record(signal)
                return
            if signal.clipped:
                self._rejections.record_clipped(signal.clipped)
            self._turns.take(signal.samples, arrival)
            if not stamped:  # called back in the publisher's thread: its next block waited for this
                self._turns.taken(self._clock.now())

    # -- runtime control --------------------------------------------------------------------------

    def set_enabled(self, enabled: bool) -> None:
        """Disabled, arriving blocks are thrown away and the utterance being collected is dropped (it
        is the robot's own voice); enabled again, the node starts clean. Health checks go on, and
        recognitions already handed over still publish."""
        with self._lock:
            self._turns.end_turn_if_over()  # an utterance already over is no robot's voice
            changed = enabled != self._in_force.enabled
            self._in_force.enabled = enabled
            if not enabled:
                self._turns.drop_utterance()
        if changed:
            _LOG.info("speechEvent %s", "enabled" if enabled else "disabled")
        if not enabled:
            self._action.disabled()

    def _use_engine(self, language: str, recognizer: Recognizer) -> None:
        """set_language: ``recognizer`` transcribes ``language`` from the next utterance on."""
        if self._turn_end is not None:  # loaded here if it hears with them, not on the worker
            self._turn_end.prepare(language, recognizer)
        with self._lock:  # utterances closed before this finish with the old engine
            self._turns.engine_or_grammar_changes()
            self._in_force.language, self._in_force.recognizer = language, recognizer
        _LOG.info("speechEvent transcribes %s now", language)

    def _use_grammar(self, grammar: Optional[Grammar]) -> None:
        """set_grammar: ``grammar`` (None: free speech) is in force from the next utterance on."""
        with self._lock:  # utterances closed before this finish with the old grammar
            self._turns.engine_or_grammar_changes()
            self._in_force.grammar = grammar
        _LOG.info("speechEvent grammar: %s", FREE_SPEECH if grammar is None else grammar.source)

    def _engine_and_grammar(self) -> Tuple[str, Recognizer, Optional[Grammar]]:
        """The language, engine and grammar in use now."""
        with self._lock:
            return self._in_force.language, self._in_force.recognizer, self._in_force.grammar

    def _refusal(self) -> Optional[str]:
        """Why an action goal cannot listen now, or None."""
        if not self.enabled:
            return DISABLED
        if not self._transport.publisher_status(SIGNAL_TOPIC).up:
            return SOUND_DETECTION_DOWN
        return None

    # -- health and diagnostics -------------------------------------------------------------------

    def _sound_detection_down(self) -> None:
        language, engine = self._engine_and_grammar()[:2]
        self._publication.publish_error(SOUND_DETECTION_DOWN, language, engine_name(engine))
        self._action.sound_detection_down()

    def _state(self, sound_detection: PublisherStatus) -> NodeState:
        with self._lock:
            return NodeState(
                engine=engine_name(self._in_force.recognizer),
                language=self._in_force.language,
                grammar="" if self._in_force.grammar is None else self._in_force.grammar.source,
                enabled=self._in_force.enabled,
                sound_detection=sound_detection,
                rejected={reason.value: count for reason, count in self._rejections.counts.items()},
                clipped=self._rejections.clipped,
                timed_out=self._watchdog.timed_out,
                utterances=self._turns.utterances,
                queued_seconds=self._queue.seconds,
                dropped=self._queue.dropped,
                partials_published=self.partials.published,
                partial_seconds=self.partials.worker_seconds,
            )
