"""publish: what recognition made of a closed utterance becomes the text on /speechEvent/text,
the action's result, the statistics and, when storing is on, the stored record."""

import functools
import logging
from dataclasses import dataclass, field
from typing import Optional

from speech_event.config import SpeechEventConfig
from speech_event.interfaces.action import ListenAction
from speech_event.interfaces.diagnostics import NodeStatistics
from speech_event.interfaces.storage import StoredUtterance, UtteranceStore
from speech_event.messages import String
from speech_event.pipeline.recognition_queue import RecognitionJob, RecognitionOutcome
from speech_event.pipeline.transcript import checked_transcript, text_to_publish
from speech_event.ports import Publisher, Transcript, Transport
from speech_event.topics import TEXT_TOPIC

_LOG = logging.getLogger("speech_event")


@dataclass
class Publication:
    """Concludes closed utterances, each once, on whichever thread recognized it."""

    config: SpeechEventConfig
    statistics: NodeStatistics
    action: ListenAction
    store: Optional[UtteranceStore]
    _publisher: Optional[Publisher] = field(default=None, init=False)

    def start(self, transport: Transport) -> None:
        """Advertise the text topic."""
        self._publisher = transport.advertise(TEXT_TOPIC, String)

    def publish(self, text: str) -> None:
        """Publish ``text`` on the text topic (nothing before ``start``)."""
        if self._publisher is not None:
            self._publisher.publish(String(text))

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
            text = text_to_publish(transcript, self.config)
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
                self.publish(text)
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
                    engine=type(recognizer).__name__,
                    transcript=transcript.text,
                    published=text,
                    recognition_time=round(took, 6),
                ),
            )
