"""The Speech Event node: message in -> validate -> assemble -> resample -> recognize -> publish.

Everything it touches comes through its constructor: the transport, the clock, the recognizer and
the executor that runs recognition off the subscriber callback. It reads no clock but the one it is
given (the stopwatch only times recognitions for diagnostics) and keeps no module state, so the
same object runs on the in-memory bus, on a real roscore, and on the robot.

This module is the wiring. The steps live in their own modules (validate, assembly, resample,
speech_screen, transcript_text), and so do the robot's interfaces around them: the services
(control), the recognise_speech action (listen_action) and /diagnostics (diagnostics).
"""

import dataclasses
import functools
import logging
import threading
import time
from typing import Callable, Dict, List, Optional

import numpy as np

from speech_event import SIGNAL_TOPIC, SOUND_DETECTION_DOWN, TEXT_TOPIC
from speech_event.assembly import UtteranceAssembler
from speech_event.config import SpeechEventConfig
from speech_event.control import SET_ENABLED_SERVICE, SET_LANGUAGE_SERVICE, RuntimeControl
from speech_event.diagnostics import (
    DIAGNOSTICS_TOPIC,
    DISCARDED_BACKLOG,
    DISCARDED_WHILE_DISABLED,
    NodeState,
    NodeStatistics,
    diagnostic_array,
)
from speech_event.engines import EngineBuilder, LanguageEngines
from speech_event.listen_action import ACTION_NAME, DISABLED, ListenAction
from speech_event.messages import (
    RECOGNISE_SPEECH,
    SET_ENABLED,
    SET_LANGUAGE,
    DiagnosticArray,
    DiagnosticStatus,
    Float32MultiArray,
    String,
)
from speech_event.periodic import Periodic
from speech_event.ports import (
    Clock,
    Executor,
    Publisher,
    PublisherStatus,
    Recognizer,
    Timer,
    Transcript,
    Transport,
)
from speech_event.recognition_queue import RecognitionJob, RecognitionOutcome, RecognitionQueue
from speech_event.rejections import RejectionLog
from speech_event.resample import resample
from speech_event.speculation import Speculation, SpeculationCounts, complete_answers, is_complete
from speech_event.speech_screen import Discard, SpeechScreen, speech_screen_for
from speech_event.storage import StoredUtterance, UtteranceStore
from speech_event.transcript_text import checked_transcript, text_to_publish
from speech_event.validate import Rejection, validate_signal

_LOG = logging.getLogger("speech_event")
# A timer may fire a little early (RosClock fires 0.1 ms early against nanosecond rounding); a
# pause timer that fires within this of its time has come due, rather than being set again.
TIMER_TOLERANCE = 1e-3


class SpeechEventNode:
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
        ``screen`` decides what is not speech (default: built from the configuration)."""
        self._config = config
        self._transport = transport
        self._clock = clock
        self._executor = executor
        self._stopwatch = stopwatch
        self._screen = screen or speech_screen_for(config)
        self._max_samples = int(config.max_message_length * config.sample_rate)
        self._assembler = UtteranceAssembler(
            config.sample_rate, config.max_utterance_length, self._screen.non_speech
        )
        self._rejections = RejectionLog(clock.now, SIGNAL_TOPIC)
        self._store = (
            UtteranceStore(config.audio_storage_dir, config.sample_rate, config.audio_storage_max_mb)
            if config.audio_storage_dir
            else None
        )
        self._statistics = NodeStatistics()
        self._queue = RecognitionQueue(config.max_backlog)
        self._running: Optional[RecognitionJob] = None  # the utterance being recognized
        self._timed_out = 0
        self._action = ListenAction(clock, self._refusal)
        self._control = RuntimeControl(
            LanguageEngines(config.language, recognizer, build_engine),
            lambda: self._language,
            self.set_enabled,
            self._use_engine,
        )
        # The subscriber callback, the clock's timers, the service handlers and the recognition
        # worker may each run on their own thread (rospy); this lock guards the assembler, the
        # pause bookkeeping, the engine in use and the enabled flag.
        self._lock = threading.Lock()
        self._language = config.language
        self._recognizer = recognizer
        self._enabled = True
        self._last_arrival = 0.0
        self._collecting_since: Optional[float] = None  # when the utterance being collected started
        self._pause_timer: Optional[Timer] = None
        # Speculative recognition (speech_event/speculation.py): at most one speculation at a time.
        self._speculation: Optional[Speculation] = None
        self._gap_timer: Optional[Timer] = None
        self._last_speculated: Optional[str] = None  # the text of this utterance's last speculation
        self._ends_early = False  # this utterance's speculation is a complete answer (early_pause)
        self._answers = complete_answers(config.complete_answers)
        self.speculations = SpeculationCounts()
        self._utterances = 0
        self._sound_detection = PublisherStatus.CONNECTED  # as the last health check found it
        self._text_publisher: Optional[Publisher] = None
        self._diagnostics_publisher: Optional[Publisher] = None
        self._periodic: List[Periodic] = []
        self._started_at = 0.0

    @property
    def rejection_counts(self) -> Dict[str, int]:
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
        with self._lock:
            return self._language

    @property
    def enabled(self) -> bool:
        with self._lock:
            return self._enabled

    def start(self) -> None:
        self._text_publisher = self._transport.advertise(TEXT_TOPIC, String)
        self._diagnostics_publisher = self._transport.advertise(DIAGNOSTICS_TOPIC, DiagnosticArray)
        self._transport.subscribe(SIGNAL_TOPIC, Float32MultiArray, self.on_signal)
        self._transport.serve(SET_ENABLED_SERVICE, SET_ENABLED, self._control.on_set_enabled)
        self._transport.serve(SET_LANGUAGE_SERVICE, SET_LANGUAGE, self._control.on_set_language)
        self._transport.serve_action(
            ACTION_NAME, RECOGNISE_SPEECH, self._action.on_goal, self._action.on_cancel
        )
        self._started_at = self._clock.now()
        self._periodic.append(
            Periodic(self._clock, self._config.health_check_period, self._check_health, self._started_at)
        )
        if self._config.verbose_mode and self._config.heartbeat_msg_period > 0:
            self._periodic.append(
                Periodic(self._clock, self._config.heartbeat_msg_period, self._heartbeat, self._started_at)
            )
        _LOG.info("speechEvent started: %s", self._config)

    def stop(self) -> None:
        """Stop the timers; an utterance still being collected is not transcribed."""
        for periodic in self._periodic:
            periodic.cancel()
        with self._lock:
            for timer in (self._pause_timer, self._gap_timer):
                if timer is not None:
                    timer.cancel()
            self._pause_timer = self._gap_timer = None
            self._drop_speculation()

    def flush_storage(self) -> None:
        """Wait until every utterance transcribed so far is stored (when storing is on)."""
        if self._store is not None:
            self._store.flush()

    # -- message in -> validate -> assemble ---------------------------------------------------------

    def on_signal(self, message: object) -> None:
        """The subscriber callback: cheap, never blocks on recognition, never raises."""
        try:
            self._take(message)
        except Exception:  # validation names every bad message; this is the last line of defence
            _LOG.exception("unexpected failure handling a message on %s; the node goes on", SIGNAL_TOPIC)

    def _take(self, message: object) -> None:
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
            samples = signal.samples
            self._last_arrival = self._clock.now()
            self._drop_speculation()  # more audio: what it transcribed is not the utterance
            self._ends_early = False
            if self._assembler.pending_samples == 0:
                self._collecting_since = self._last_arrival
                self._action.utterance_started(self._last_arrival)
            completed = self._assembler.add(samples)
            if completed:  # cut at the length limit: what is left is a new utterance to speculate on
                self._last_speculated = None
            for index, utterance in enumerate(completed):
                # Cut at the length limit: the speech goes on in the next utterance.
                self._submit(utterance, index < len(completed) - 1 or self._assembler.pending_samples > 0)
            if self._pause_timer is None:
                self._pause_timer = self._clock.call_at(
                    self._last_arrival + self._config.speech_pause_period, self._on_pause_timer
                )
            if self._config.speculative_recognition and self._gap_timer is None:
                self._gap_timer = self._clock.call_at(
                    self._last_arrival + self._config.speculation_gap, self._on_gap_timer
                )

    def _pause(self) -> float:
        """The pause that ends the utterance being collected (shorter for a complete answer)."""
        return self._config.early_pause if self._ends_early else self._config.speech_pause_period

    def _on_pause_timer(self) -> None:
        # One timer per utterance rather than one per block: when it fires early (more blocks came
        # since it was set) it is set again for the pause after the latest block.
        with self._lock:
            self._pause_timer = None
            due = self._last_arrival + self._pause()
            if self._clock.now() < due - TIMER_TOLERANCE:
                self._pause_timer = self._clock.call_at(due, self._on_pause_timer)
                return
            self._last_speculated, self._ends_early = None, False
            utterance = self._assembler.close()
            if utterance is not None:
                self._submit(utterance, more_follows=False)

    # -- speculative recognition (speech_event/speculation.py) ------------------------------------

    def _on_gap_timer(self) -> None:
        with self._lock:
            self._gap_timer = None
            due = self._last_arrival + self._config.speculation_gap
            if self._clock.now() < due - TIMER_TOLERANCE:
                self._gap_timer = self._clock.call_at(due, self._on_gap_timer)
                return
            self._maybe_speculate()

    def _maybe_speculate(self) -> None:
        """Under the lock: speculate on the utterance being collected if its gap has passed, the
        worker is idle (closed utterances first) and nothing is speculated on yet. Only with an
        engine that can be stopped: one that cannot would run a speculation made worthless to its
        end, and an utterance closing meanwhile would wait for it (pocketsphinx, whose texts also
        depend on what it heard before: see the README)."""
        stoppable = callable(getattr(self._recognizer, "cancel", None))
        wanted = self._config.speculative_recognition and stoppable and self._enabled
        wanted = wanted and self._assembler.pending_samples > 0
        idle = self._running is None and self._queue.waiting == 0 and self._speculation is None
        gap = self._last_arrival + self._config.speculation_gap
        if not (wanted and idle and self._gap_timer is None and self._clock.now() >= gap - TIMER_TOLERANCE):
            return
        audio = self._assembler.peek()
        speculation = Speculation(audio.size, self._recognizer)
        self._speculation = speculation
        self.speculations.started += 1
        speculation.handle = self._executor.submit(functools.partial(self._speculate, speculation, audio))

    def _speculate(self, speculation: Speculation, audio: np.ndarray) -> None:
        """An executor job: transcribe the utterance so far; publish it only if it closed as it is."""
        with self._lock:
            if speculation.cancelled:
                return
            speculation.running = True
        outcome = self._recognize(audio, speculation.recognizer)
        with self._lock:
            speculation.running = False
            if speculation.watchdog is not None:
                speculation.watchdog.cancel()
            if speculation.cancelled:
                self.speculations.wasted_seconds += outcome.took
                return
            speculation.outcome = outcome
            job = speculation.adopted
            if job is None:  # the pause has not ended: maybe the turn may end early
                self._note_speculated(speculation, outcome)
                return
            self._speculation = None
            self.speculations.used += 1
        self._conclude(job, outcome)

    def _note_speculated(self, speculation: Speculation, outcome: RecognitionOutcome) -> None:
        """Under the lock: a complete answer ends the turn after early_pause, not the whole pause."""
        text = getattr(outcome.answer, "text", "")
        grammar_mode = bool(getattr(speculation.recognizer, "whole_phrases", False))
        complete = isinstance(text, str) and is_complete(
            text, self._last_speculated, grammar_mode, self._answers
        )
        self._last_speculated = text
        if not (complete and self._config.early_pause > 0):
            return
        self._ends_early = True
        if self._pause_timer is not None:
            self._pause_timer.cancel()
        self._pause_timer = self._clock.call_at(
            max(self._clock.now(), self._last_arrival + self._config.early_pause), self._on_pause_timer
        )

    def _drop_speculation(self) -> None:
        """Under the lock: the speculation being collected for is worthless now (not one that a
        closed utterance adopted: that one is its recognition)."""
        speculation = self._speculation
        if speculation is None or speculation.adopted is not None:
            return
        self._speculation = None
        speculation.cancel()
        if speculation.outcome is not None:
            self.speculations.wasted_seconds += speculation.outcome.took

    def _submit(self, audio: np.ndarray, more_follows: bool) -> None:
        """Hand a closed utterance to recognition with the engine in use now (under the lock)."""
        self._utterances += 1
        number, closed_at, recognizer = self._utterances, self._clock.now(), self._recognizer
        started_at = self._collecting_since if self._collecting_since is not None else closed_at
        if not more_follows:
            self._collecting_since = None
        seconds = audio.size / self._config.sample_rate
        self._statistics.queued(seconds)
        self._action.utterance_closed(number, started_at, more_follows)
        job = RecognitionJob(number, started_at, closed_at, audio, recognizer, self._language, seconds)
        speculation = self._speculation
        if speculation is not None and speculation.adopted is None:
            if not speculation.is_for(audio.size, recognizer):
                self._drop_speculation()  # another utterance closed: it comes first
            elif speculation.outcome is None:
                speculation.adopted = job  # still running: its end publishes this utterance
                speculation.watchdog = self._watch(job)  # its recognition starts now, as it were
                return
            else:  # done: publish its result now, nothing to recognize again
                self._speculation = None
                self.speculations.used += 1
                job = dataclasses.replace(job, ready=speculation.outcome)
        for dropped in self._queue.put(job):
            self._statistics.finished(dropped.seconds)
            self._statistics.discarded(DISCARDED_BACKLOG)
            self._action.utterance_done(dropped.number, None)
        self._executor.submit(self._run_next, recognizes=job.ready is None)

    # -- resample -> screen -> recognize -> publish (on the executor) -------------------------------

    def _run_next(self) -> None:
        """One executor job: the oldest waiting utterance (none when it was dropped), watched."""
        watchdog: Optional[Timer] = None
        with self._lock:
            job = self._queue.take()
            if job is None:
                return
            self._running = job
            watchdog = self._watch(job)
        try:
            self._recognize_and_publish(job)
        finally:
            with self._lock:
                self._running = None
                if watchdog is not None:
                    watchdog.cancel()
                self._maybe_speculate()  # the utterance being collected waited for this one

    def _watch(self, job: RecognitionJob) -> Optional[Timer]:
        """Under the lock: the recognition of ``job`` starts; past recognition_timeout it is overdue."""
        if self._config.recognition_timeout <= 0:
            return None
        return self._clock.call_at(
            self._clock.now() + self._config.recognition_timeout, functools.partial(self._overdue, job)
        )

    def _overdue(self, job: RecognitionJob) -> None:
        with self._lock:  # under the lock, so a cancel never reaches the next utterance's run
            speculation = self._speculation
            adopted = speculation is not None and speculation.adopted is job and speculation.running
            if self._running is not job and not adopted:
                return
            self._timed_out += 1
            cancel: Optional[Callable[[], None]] = getattr(job.recognizer, "cancel", None)
            _LOG.error(
                "recognition of utterance %d (%.2f s) still runs after recognition_timeout %.0f s: %s",
                job.number,
                job.seconds,
                self._config.recognition_timeout,
                "cancelling it"
                if cancel
                else "this engine cannot be cancelled; later utterances wait, bounded by max_backlog",
            )
            if cancel is not None:
                cancel()

    def _recognize_and_publish(self, job: RecognitionJob) -> None:
        outcome = job.ready if job.ready is not None else self._recognize(job.audio, job.recognizer)
        self._conclude(job, outcome)

    def _recognize(self, audio: np.ndarray, recognizer: Recognizer) -> RecognitionOutcome:
        """Resample, screen, transcribe (for a closed utterance or a speculation)."""
        try:
            speech = resample(audio, self._config.sample_rate, recognizer.sample_rate)
            discard = self._screen.discard(speech, recognizer.sample_rate)
            if discard is not None:
                return RecognitionOutcome(discard=discard)
            began = self._stopwatch()
            answer = recognizer.transcribe(speech)
            return RecognitionOutcome(answer, took=self._stopwatch() - began)
        # A failed recognition must not stop the node; SystemExit from an engine is a failure like
        # any other. It is said when the utterance concludes (a cancelled speculation never does).
        except (Exception, SystemExit) as problem:
            return RecognitionOutcome(error=problem)

    def _conclude(self, job: RecognitionJob, outcome: RecognitionOutcome) -> None:
        """Publish what recognition made of a closed utterance, tell the action, store it."""
        number, recognizer, seconds = job.number, job.recognizer, job.seconds
        discard, took = outcome.discard, outcome.took
        text: Optional[str] = None
        transcript = Transcript("")
        try:
            if outcome.error is not None:
                raise outcome.error
            if discard is None:
                self._statistics.transcribed(seconds, took)
                # An engine that answers with something else than a transcript fails the same way.
                transcript = checked_transcript(outcome.answer, number)
        except (Exception, SystemExit):
            _LOG.exception("recognition of utterance %d (%.2f s) failed", number, seconds)
        finally:
            self._statistics.finished(seconds)
        if discard is not None:
            self._statistics.discarded(discard.value)
            _LOG.info("utterance %d (%.2f s) is not transcribed: %s", number, seconds, discard.value)
        else:
            text = text_to_publish(transcript, self._config)
            _LOG.info("utterance %d (%.2f s): %r -> %r", number, seconds, transcript.text, text)
            if text is not None:
                self._publish(text)
                self._statistics.published()
        self._action.utterance_done(number, None if discard is not None else text or "")
        if self._store is not None:  # after publishing: storing never delays or loses a transcript
            self._store.save(
                number,
                job.started_at,
                job.audio,
                functools.partial(
                    StoredUtterance,
                    language=job.language,
                    engine=type(recognizer).__name__,
                    transcript=transcript.text,
                    published=text,
                    recognition_time=round(took, 6),
                ),
            )

    # -- runtime control --------------------------------------------------------------------------

    def set_enabled(self, enabled: bool) -> None:
        """Disabled, arriving blocks are thrown away and the utterance being collected is dropped (it
        is the robot's own voice); enabled again, the node starts clean. Health checks go on, and
        recognitions already handed over still publish."""
        with self._lock:
            changed = enabled != self._enabled
            self._enabled = enabled
            if not enabled:
                self._drop_speculation()
                self._last_speculated, self._ends_early = None, False
                if self._pause_timer is not None:
                    self._pause_timer.cancel()
                    self._pause_timer = None
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
            self._drop_speculation()
            self._language, self._recognizer = language, recognizer
        _LOG.info("speechEvent transcribes %s now", language)

    def _refusal(self) -> Optional[str]:
        """Why an action goal cannot listen now, or None."""
        if not self.enabled:
            return DISABLED
        if not self._transport.publisher_status(SIGNAL_TOPIC).up:
            return SOUND_DETECTION_DOWN
        return None

    # -- health and diagnostics -------------------------------------------------------------------

    def _check_health(self) -> None:
        status = self._transport.publisher_status(SIGNAL_TOPIC)
        self._sound_detection = status
        if not status.up:
            self._publish(SOUND_DETECTION_DOWN)  # published first: a log call may be slow (rosout)
            _LOG.warning("soundDetection is down on %s: %s", SIGNAL_TOPIC, status.value)
            self._action.sound_detection_down()
        if self._diagnostics_publisher is not None:
            self._diagnostics_publisher.publish(diagnostic_array(self._clock.now(), self.diagnostic_status()))

    def diagnostic_status(self) -> DiagnosticStatus:
        with self._lock:
            state = NodeState(
                engine=type(self._recognizer).__name__,
                language=self._language,
                enabled=self._enabled,
                sound_detection=self._sound_detection,
                rejected={reason.value: count for reason, count in self._rejections.counts.items()},
                clipped=self._rejections.clipped,
                timed_out=self._timed_out,
            )
        return self._statistics.status(state, [reason.value for reason in Discard])

    def _publish(self, text: str) -> None:
        if self._text_publisher is not None:  # None only before start()
            self._text_publisher.publish(String(text))

    def _heartbeat(self) -> None:
        with self._lock:
            clipped, timed_out = self._rejections.clipped, self._timed_out
        _LOG.info(
            "speechEvent running: %d utterances so far, rejected messages %s, clipped messages %d, "
            "%.1f s of speech waiting for recognition, %d dropped (max_backlog), %d timed out",
            self._utterances,
            {reason: count for reason, count in self.rejection_counts.items() if count},
            clipped,
            self._queue.seconds,
            self._queue.dropped,
            timed_out,
        )
