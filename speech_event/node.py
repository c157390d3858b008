"""The Speech Event node: message in -> validate -> assemble -> resample -> recognize -> publish.

Everything it touches comes through its constructor: the transport, the clock, the recognizer and
the executor that runs recognition off the subscriber callback. It reads no wall clock and keeps
no module state, so the same object runs on the in-memory bus, on a real roscore, and on the robot.
"""

import logging
import threading
from typing import Dict, List, Optional

import numpy as np

from speech_event import SIGNAL_TOPIC, SOUND_DETECTION_DOWN, TEXT_TOPIC
from speech_event.assembly import UtteranceAssembler
from speech_event.config import SpeechEventConfig
from speech_event.messages import Float32MultiArray, String
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
from speech_event.rejections import RejectionLog
from speech_event.resample import resample
from speech_event.storage import UtteranceStore
from speech_event.transcript_text import text_to_publish
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
    ) -> None:
        self._config = config
        self._transport = transport
        self._clock = clock
        self._recognizer = recognizer
        self._executor = executor
        self._max_samples = int(config.max_message_length * config.sample_rate)
        self._assembler = UtteranceAssembler(config.sample_rate, config.max_utterance_length)
        self._rejections = RejectionLog(clock.now, SIGNAL_TOPIC)
        self._store = (
            UtteranceStore(config.audio_storage_dir, config.sample_rate) if config.audio_storage_dir else None
        )
        # The subscriber callback, the clock's timers and the recognition worker may each run on
        # their own thread (rospy); this lock guards the assembler and the pause bookkeeping.
        self._lock = threading.Lock()
        self._last_arrival = 0.0
        self._pause_timer: Optional[Timer] = None
        self._utterances = 0
        self._text_publisher: Optional[Publisher] = None
        self._periodic: List[Periodic] = []

    @property
    def rejection_counts(self) -> Dict[str, int]:
        with self._lock:
            return {reason.value: count for reason, count in self._rejections.counts.items()}

    @property
    def pending_samples(self) -> int:
        """Samples of the utterance being collected, not yet handed to recognition."""
        with self._lock:
            return self._assembler.pending_samples

    def start(self) -> None:
        self._text_publisher = self._transport.advertise(TEXT_TOPIC, String)
        self._transport.subscribe(SIGNAL_TOPIC, Float32MultiArray, self.on_signal)
        self._periodic.append(Periodic(self._clock, self._config.health_check_period, self._check_health))
        if self._config.verbose_mode and self._config.heartbeat_msg_period > 0:
            self._periodic.append(Periodic(self._clock, self._config.heartbeat_msg_period, self._heartbeat))
        _LOG.info("speechEvent started: %s", self._config)

    def stop(self) -> None:
        """Stop the timers; an utterance still being collected is not transcribed."""
        for periodic in self._periodic:
            periodic.cancel()
        with self._lock:
            if self._pause_timer is not None:
                self._pause_timer.cancel()
                self._pause_timer = None

    def on_signal(self, message: object) -> None:
        """The subscriber callback: cheap, never blocks on recognition."""
        samples = validate_signal(message, self._max_samples)
        with self._lock:  # rospy may call back from two connections at once (a restart overlapping)
            if isinstance(samples, Rejection):
                self._rejections.record(samples)
                return
            self._last_arrival = self._clock.now()
            for utterance in self._assembler.add(samples):
                self._submit(utterance)
            if self._pause_timer is None:
                self._pause_timer = self._clock.call_at(
                    self._last_arrival + self._config.speech_pause_period, self._on_pause_timer
                )

    def _on_pause_timer(self) -> None:
        # One timer per utterance rather than one per block: when it fires early (more blocks came
        # since it was set) it is set again for the pause after the latest block.
        with self._lock:
            self._pause_timer = None
            due = self._last_arrival + self._config.speech_pause_period
            if self._clock.now() < due - TIMER_TOLERANCE:
                self._pause_timer = self._clock.call_at(due, self._on_pause_timer)
                return
            utterance = self._assembler.close()
            if utterance is not None:
                self._submit(utterance)

    def _submit(self, audio: np.ndarray) -> None:
        self._utterances += 1
        number, closed_at = self._utterances, self._clock.now()
        self._executor.submit(lambda: self._recognize_and_publish(number, closed_at, audio))

    def _recognize_and_publish(self, number: int, closed_at: float, audio: np.ndarray) -> None:
        seconds = audio.size / self._config.sample_rate
        try:
            if self._store is not None:
                self._store.save(number, closed_at, audio)
            speech = resample(audio, self._config.sample_rate, self._recognizer.sample_rate)
            transcript = self._recognizer.transcribe(speech)
        except Exception:  # a failed recognition must not stop the node
            _LOG.exception("recognition of utterance %d (%.2f s) failed", number, seconds)
            transcript = Transcript("")
        text = text_to_publish(transcript, self._config)
        _LOG.info("utterance %d (%.2f s): %r -> %r", number, seconds, transcript.text, text)
        if text is not None:
            self._publish(text)

    def _check_health(self) -> None:
        status = self._transport.publisher_status(SIGNAL_TOPIC)
        if status is not PublisherStatus.CONNECTED:
            _LOG.warning("soundDetection is down on %s: %s", SIGNAL_TOPIC, status.value)
            self._publish(SOUND_DETECTION_DOWN)

    def _publish(self, text: str) -> None:
        if self._text_publisher is not None:  # None only before start()
            self._text_publisher.publish(String(text))

    def _heartbeat(self) -> None:
        _LOG.info(
            "speechEvent running: %d utterances so far, rejected messages %s",
            self._utterances,
            {reason: count for reason, count in self.rejection_counts.items() if count},
        )
