"""Step 7 of the pipeline, publish: what recognition made of a closed utterance becomes the text
on /speechEvent/text, the action's result, the statistics and, when storing is on, the stored
record; with each text published, and each partial text (/speechEvent/partial), a message on
/speechEvent/transcript with its confidence, language, engine and the times of its utterance's
blocks."""

import functools
import logging
from dataclasses import dataclass, field
from typing import Callable, Optional, Protocol

from speech_event.config import SpeechEventConfig
from speech_event.interfaces.action import ListenAction
from speech_event.interfaces.diagnostics import DISCARDED_BACKLOG, NodeStatistics
from speech_event.messages import NO_CONFIDENCE, NO_UTTERANCE, String, TranscriptMessage
from speech_event.pipeline.recognition_queue import RecognitionJob, RecognitionOutcome
from speech_event.pipeline.storage import StoredUtterance, UtteranceStore
from speech_event.pipeline.transcript import checked_transcript, styled, text_to_publish
from speech_event.ports import Publisher, Transcript, Transport, engine_name
from speech_event.topics import PARTIAL_TOPIC, SPEECH_NOT_RECOGNIZED, TEXT_TOPIC, TRANSCRIPT_TOPIC

_LOG = logging.getLogger("speech_event")


@dataclass(frozen=True)
class TextOrigin:
    """Where a text comes from, for its /speechEvent/transcript message."""

    language: str
    engine: str  # the engine's class name
    first_block: float  # when the utterance's first block arrived (NO_UTTERANCE: no utterance)
    last_block: float  # when its last block, so far for a partial, arrived
    # A grammar was in force: the text is its phrase, published as the grammar spells it.
    phrase: bool = False


class Publishes(Protocol):
    """What the recognition worker's jobs end in: Publication, or a test's recorder."""

    def conclude(self, job: RecognitionJob, outcome: RecognitionOutcome) -> None: ...

    def dropped(self, job: RecognitionJob) -> None: ...

    def partial(self, transcript: Transcript, origin: TextOrigin) -> None: ...


@dataclass
class Publication:
    """Concludes closed utterances, each once, on whichever thread recognized it."""

    config: SpeechEventConfig
    statistics: NodeStatistics
    action: ListenAction
    store: Optional[UtteranceStore]
    now: Callable[[], float]  # the node's clock: the transcript messages' stamps
    _text: Optional[Publisher] = field(default=None, init=False)
    _partial: Optional[Publisher] = field(default=None, init=False)
    _transcript: Optional[Publisher] = field(default=None, init=False)

    def start(self, transport: Transport) -> None:
        """Advertise the text, partial and transcript topics."""
        self._text = transport.advertise(TEXT_TOPIC, String)
        self._partial = transport.advertise(PARTIAL_TOPIC, String)
        self._transcript = transport.advertise(TRANSCRIPT_TOPIC, TranscriptMessage)

    def publish(
        self, text: str, origin: TextOrigin, confidence: Optional[float] = None, written: Optional[str] = None
    ) -> None:
        """Publish a final ``text`` on the text topic, and its transcript message with the text as
        the engine ``written`` it (default: ``text``); nothing before ``start``."""
        if self._text is not None:
            self._text.publish(String(text))
        self._publish_transcript(text if written is None else written, True, confidence, origin)

    def publish_error(self, text: str, language: str, engine: str) -> None:
        """Publish an error of no utterance (SOUND_DETECTION_DOWN) as a final text."""
        self.publish(text, TextOrigin(language, engine, NO_UTTERANCE, NO_UTTERANCE))

    def partial(self, transcript: Transcript, origin: TextOrigin) -> None:
        """Publish the text so far of the utterance being spoken (as text_style writes it), and its
        transcript message (as the engine wrote it)."""
        if self._partial is not None:
            text = transcript.text if origin.phrase else styled(transcript.text, self.config.text_style)
            self._partial.publish(String(text))
        self._publish_transcript(transcript.text, False, transcript.confidence, origin)

    def _publish_transcript(
        self, text: str, final: bool, confidence: Optional[float], origin: TextOrigin
    ) -> None:
        if self._transcript is None:
            return
        message = TranscriptMessage(
            stamp=self.now(),
            text=text,
            final=final,
            confidence=NO_CONFIDENCE if confidence is None else float(confidence),
            language=origin.language,
            engine=origin.engine,
            first_block=origin.first_block,
            last_block=origin.last_block,
        )
        self._transcript.publish(message)

    def dropped(self, job: RecognitionJob) -> None:
        """``job`` was dropped unrecognized to keep within max_backlog: counted, and the action told."""
        self.statistics.finished(job.seconds)
        self.statistics.discarded(DISCARDED_BACKLOG)
        self.action.utterance_done(job.number, None)

    def conclude(self, job: RecognitionJob, outcome: RecognitionOutcome) -> None:
        """Publish what recognition made of ``job``, tell the action, store it."""
        number, recognizer, seconds = job.number, job.recognizer, job.seconds
        discard, took = outcome.discard, outcome.took
        text: Optional[str] = None
        transcript = Transcript("")
        try:
            if outcome.error is not None:
                raise outcome.error
            if discard is None:
                self.statistics.transcribed(seconds, took)
                # An engine that answers with something else than a transcript fails the same way.
                transcript = checked_transcript(outcome.answer, number)
        except (Exception, SystemExit):
            _LOG.exception("recognition of utterance %d (%.2f s) failed", number, seconds)
        finally:
            self.statistics.finished(seconds)
        if discard is not None:
            self.statistics.discarded(discard.value)
            _LOG.info("utterance %d (%.2f s) is not transcribed: %s", number, seconds, discard.value)
        else:
            phrase = job.grammar is not None
            text = text_to_publish(transcript, self.config, phrase)
            if transcript.rejected is not None:
                self.statistics.out_of_grammar()
                _LOG.info(
                    "utterance %d (%.2f s) is no phrase of the grammar (nearest: %r) -> %r",
                    number,
                    seconds,
                    transcript.rejected,
                    text,
                )
            else:
                _LOG.info("utterance %d (%.2f s): %r -> %r", number, seconds, transcript.text, text)
            if text is not None:
                engine = engine_name(recognizer)
                origin = TextOrigin(job.language, engine, job.started_at, job.last_block_at, phrase)
                written = transcript.text.strip() if text != SPEECH_NOT_RECOGNIZED else text
                self.publish(text, origin, transcript.confidence, written)
                self.statistics.published()
        self.action.utterance_done(number, None if discard is not None else text or "")
        if self.store is not None:  # after publishing: storing never delays or loses a transcript
            self.store.save(
                number,
                job.started_at,
                job.audio,
                functools.partial(
                    StoredUtterance,
                    language=job.language,
                    engine=engine_name(recognizer),
                    transcript=transcript.text,
                    published=text,
                    recognition_time=round(took, 6),
                ),
            )
