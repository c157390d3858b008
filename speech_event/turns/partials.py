"""Partial results (issue 20): the text of the utterance being spoken, so far.

While an utterance is collected, at most every ``partial_period`` seconds (counted from its first
block, then from the start of its last partial), and only when the recognition worker is idle
(closed utterances and speculations come first), the node asks the engine for the text of the
audio so far. It publishes the text on /speechEvent/partial when it is not empty, passes
``confidence`` and differs from the utterance's last partial. Two ways, by what the engine can do:

- An engine that can be stopped (``Stoppable``: NeMo, Whisper, the fake) transcribes the audio so
  far from its start, as a speculation does (a ``Speculation`` that is never adopted). It is
  cancelled, the engine stopped, when the utterance closes or a speculation wants the worker, so no
  final text waits for it. More audio does not cancel it: its text is still the text so far.
- An ``Incremental`` engine (pocketsphinx) is fed only the audio that is new since its last
  partial, on a decoder of its own that the final texts never touch. The feed goes in chunks of
  FEED_SECONDS and stops between two once the utterance has closed.

A speculation (speech_event/turns/speculation.py) that ends with more audio to come, or waiting for the
pause to end, also gives the text so far: it is published as a partial too, when it is new.

A partial never publishes on /speechEvent/text and never ends a turn: final texts are exactly those
of the node without partials, at the same times (tests/turns/test_partials.py, test_every_scenario.py).
"""

from dataclasses import dataclass
from typing import Optional

from speech_event.config import SpeechEventConfig
from speech_event.grammar import Grammar
from speech_event.pipeline.recognition_queue import RecognitionOutcome
from speech_event.pipeline.resample import StreamResampler
from speech_event.pipeline.transcript import proper_transcript
from speech_event.ports import (
    TIMER_TOLERANCE,
    Audio,
    Cancellable,
    Incremental,
    Recognizer,
    Stoppable,
    Transcript,
)
from speech_event.turns.speculation import Speculation

# An Incremental engine is fed this much audio at a time: a closing utterance waits for at most
# one chunk (pocketsphinx: about 15 ms of work for 0.1 s of audio on this project's CI machine).
FEED_SECONDS = 0.1


@dataclass
class PartialCounts:
    """How partial results fared on this node."""

    started: int = 0  # partial runs and feeds handed to the worker
    published: int = 0
    worker_seconds: float = 0.0  # engine time they took


class PartialFeed:
    """One utterance fed to an Incremental engine's partial decoder, as the audio comes.

    ``fed`` and ``closed`` are written under the node's lock; ``feed`` runs on the worker."""

    def __init__(
        self, recognizer: Incremental, grammar: Optional[Grammar], from_rate: int, to_rate: int
    ) -> None:
        self.recognizer = recognizer
        self.grammar = grammar
        self._resampler = StreamResampler(from_rate, to_rate)
        self._chunk = max(1, int(FEED_SECONDS * from_rate))
        self._begun = False
        self.fed = 0  # samples handed to the worker, at the node's rate
        self.closed = False  # the utterance closed, or the engine or grammar changed
        self.handle: Optional[Cancellable] = None

    def feed(self, audio: Audio) -> Optional[Transcript]:
        """The text so far after ``audio``, the next samples of the utterance; None when the
        utterance closed meanwhile (the rest is not fed: the decoder is dropped). Raises what the
        engine raises."""
        if not self._begun:
            self.recognizer.begin_partial(self.grammar)
            self._begun = True
        transcript: Optional[Transcript] = None
        for start in range(0, audio.size, self._chunk):
            if self.closed:  # read without the lock: at worst one chunk more is fed
                return None
            transcript = self.recognizer.feed_partial(self._resampler(audio[start : start + self._chunk]))
        return transcript


class PartialRules:
    """When to ask for a partial, and which texts to publish. At most one partial at a time; every
    method is called under the node's lock."""

    def __init__(self, config: SpeechEventConfig) -> None:
        self._period = config.partial_period
        self._confidence = config.confidence
        self._sample_rate = config.sample_rate
        self.counts = PartialCounts()
        self.run: Optional[Speculation] = None  # a Stoppable engine's partial run
        self.feed: Optional[PartialFeed] = None  # this utterance's feed of an Incremental engine
        self._since = 0.0  # when the utterance started, or its last partial did
        self._covered = 0  # samples of the utterance that the last finished run transcribed
        self._last_text: Optional[str] = None

    @property
    def on(self) -> bool:
        """Whether partial results are wanted at all (partial_period is not 0)."""
        return self._period > 0

    def due(self) -> float:
        """When the next partial may start."""
        return self._since + self._period

    def begin(self, now: float) -> None:
        """An utterance starts (its first block came at ``now``): its first partial is due one
        period later, and its texts are compared afresh."""
        self.drop()
        self._since, self._covered, self._last_text = now, 0, None

    def may_start(self, recognizer: Recognizer, worker_idle: bool, pending: int, now: float) -> bool:
        """Whether to ask ``recognizer`` for the text of the ``pending`` samples collected so far."""
        busy = self.run is not None or (self.feed is not None and self.feed.handle is not None)
        able = isinstance(recognizer, (Stoppable, Incremental))
        return (
            self.on
            and able
            and worker_idle
            and not busy
            and pending > self._done()
            and now >= self.due() - TIMER_TOLERANCE
        )

    def start_run(
        self, samples: int, recognizer: Recognizer, grammar: Optional[Grammar], now: float
    ) -> Speculation:
        """A Stoppable engine's run on the first ``samples`` of the utterance."""
        self._since = now
        self.counts.started += 1
        self.run = Speculation(samples, recognizer, grammar)
        return self.run

    def start_feed(self, recognizer: Incremental, grammar: Optional[Grammar], now: float) -> PartialFeed:
        """The utterance's feed of an Incremental engine (made at its first partial); the caller
        hands it the samples from ``feed.fed`` on and sets ``fed`` and ``handle``."""
        self._since = now
        self.counts.started += 1
        if self.feed is None:
            self.feed = PartialFeed(recognizer, grammar, self._sample_rate, recognizer.sample_rate)
        return self.feed

    def drop(self) -> None:
        """Cancel the partial in progress (the utterance closed or was dropped, or the worker is
        wanted); an Incremental engine's feed starts over with the next partial."""
        run, self.run = self.run, None
        if run is not None:
            run.cancel()
        feed, self.feed = self.feed, None
        if feed is not None:
            feed.closed = True
            if feed.handle is not None:
                feed.handle.cancel()

    def finished(self, run: Speculation, outcome: RecognitionOutcome) -> Optional[Transcript]:
        """A run ended: the partial to publish, or None (cancelled, or nothing new to say)."""
        self.counts.worker_seconds += outcome.took
        run.running = False
        if run.cancelled or run is not self.run:
            return None
        self.run, self._covered = None, run.samples
        return self._new_text(outcome.answer)

    def fed(self, feed: PartialFeed, answer: Optional[Transcript], took: float) -> Optional[Transcript]:
        """A feed job ended: the partial to publish, or None."""
        self.counts.worker_seconds += took
        feed.handle = None
        if feed.closed or feed is not self.feed or answer is None:
            return None
        return self._new_text(answer)

    def spoken(self, samples: int, answer: object) -> Optional[Transcript]:
        """A speculation on the first ``samples`` of the utterance ended, and more audio may come:
        its text is the text so far, a partial like any other (None: partials are off, or it
        says nothing new)."""
        if not self.on:
            return None
        self._covered = max(self._covered, samples)
        return self._new_text(answer)

    def _done(self) -> int:
        return self.feed.fed if self.feed is not None else self._covered

    def _new_text(self, answer: object) -> Optional[Transcript]:
        transcript = proper_transcript(answer)
        if transcript is None:
            return None  # a failed or stopped run: its final recognition will say why
        text = transcript.text.strip()
        confident = transcript.confidence is None or transcript.confidence >= self._confidence
        if not text or not confident or text == self._last_text:
            return None
        self._last_text = text
        self.counts.published += 1
        return Transcript(text, transcript.confidence)
