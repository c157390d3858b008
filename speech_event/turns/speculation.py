"""Speculative recognition: the utterance so far, transcribed while the speaker pauses (issue 11).

When no block has come for ``speculation_gap`` and the recognition worker is idle (closed
utterances always come first), the node hands the audio collected so far to the worker. If the
pause then ends with no new block, the closed utterance *is* that audio, so the speculation's
result is its result: published at once, or as soon as the speculation ends, instead of being
recognized again from the start. A block that arrives first makes the speculation worthless: it
is cancelled (with the engine's ``stop`` where it has one, onnxruntime's RunOptions.terminate;
one that cannot be stopped runs on, its result unused) and its engine time counted as wasted. A
speculation never publishes by itself, so the node publishes exactly the texts it would publish
without speculating, never later.

Early end of turn (``early_pause``, opt-in) builds on it: a speculation whose text is a complete
answer lets the pause end after ``early_pause`` instead of ``speech_pause_period``.
"""

from dataclasses import dataclass
from typing import FrozenSet, Optional

from speech_event.config import SpeechEventConfig
from speech_event.grammar import Grammar
from speech_event.pipeline.recognition_queue import RecognitionJob, RecognitionOutcome
from speech_event.pipeline.transcript import proper_transcript
from speech_event.ports import Cancellable, Recognizer, Stoppable, Timer


@dataclass
class SpeculationCounts:
    """How speculation fared on this node."""

    started: int = 0
    used: int = 0  # their result was the closed utterance's
    wasted_seconds: float = 0.0  # engine time of speculations that more audio made worthless


class Speculation:
    """One speculation: the first ``samples`` of the utterance being collected, with one engine
    and the grammar in force (None: free speech).

    Every field is read and written under the node's lock."""

    def __init__(self, samples: int, recognizer: Recognizer, grammar: Optional[Grammar]) -> None:
        self.samples = samples
        self.recognizer = recognizer
        self.grammar = grammar
        self.handle: Optional[Cancellable] = None
        self.running = False
        self.cancelled = False
        self.outcome: Optional[RecognitionOutcome] = None
        # The closed utterance this speculation turned out to be: its outcome is that utterance's.
        self.adopted: Optional[RecognitionJob] = None
        self.watchdog: Optional[Timer] = None  # recognition_timeout, once adopted while running
        # Whether its text is complete by itself (no comparison with the speculation before it,
        # which depends on which speculations ran): what a decision on the end of speech takes.
        self.complete = False
        # Whether its audio ends at the last block that came (a pause of the gate follows, in no
        # samples), not at a cut inside the samples: what a turn-end model is told.
        self.at_last_block = True
        # Whether the turn-end model hears it (free speech, where turn_end_model hears the engine).
        self.hears_turn_end = False

    def is_for(self, job: RecognitionJob) -> bool:
        """Whether a closed utterance is exactly the audio this speculation transcribes, for the
        same engine and grammar."""
        return (
            not self.cancelled
            and self.samples == job.audio.size
            and self.recognizer is job.recognizer
            and self.grammar == job.grammar
        )

    def cancel(self) -> None:
        """Superseded: never run it, or stop it where the engine allows."""
        self.cancelled = True
        if self.handle is not None:
            self.handle.cancel()
        if self.running and isinstance(self.recognizer, Stoppable):
            self.recognizer.stop()


class SpeculationRules:
    """When to speculate, when a closed utterance adopts a speculation, when to drop one, and
    whether its text ends the turn early. At most one speculation at a time; every method is
    called under the node's lock."""

    def __init__(self, config: SpeechEventConfig) -> None:
        self._wanted = config.speculative_recognition
        self._answers = complete_answers(config.complete_answers)
        # turn_end_text false: where the turn-end model hears, any text is complete and it decides
        self._audio_alone = not config.turn_end_text
        self.counts = SpeculationCounts()
        self.current: Optional[Speculation] = None
        self._last_text: Optional[str] = None  # the text of this utterance's last speculation

    def may_start(self, recognizer: Recognizer, worker_idle: bool, at_end_of_speech: bool = False) -> bool:
        """Whether to speculate now with ``recognizer``, only while the worker is idle (closed
        utterances first), one at a time. With an engine that cannot be stopped (pocketsphinx),
        only on the audio up to where the speech so far ended (``at_end_of_speech``: where
        ``decides_at_end_of_speech``): the decision on the end of the turn needs that text
        whatever it costs. Elsewhere such a speculation, made worthless by the next block, would
        run to its end, and an utterance closing meanwhile would wait for it."""
        able = isinstance(recognizer, Stoppable) or at_end_of_speech
        return self._wanted and able and worker_idle and self.current is None

    def start(self, samples: int, recognizer: Recognizer, grammar: Optional[Grammar]) -> Speculation:
        """Speculate on the first ``samples`` of the utterance being collected."""
        self.current = Speculation(samples, recognizer, grammar)
        self.counts.started += 1
        return self.current

    def drop(self, keep: Optional[int] = None) -> None:
        """The speculation being collected for is worthless now (not one that a closed utterance
        adopted: that one is its recognition; nor one on the first ``keep`` samples, the audio a
        decision on the end of speech will cut at)."""
        speculation = self.current
        if speculation is None or speculation.adopted is not None or speculation.samples == keep:
            return
        self.current = None
        speculation.cancel()
        if speculation.outcome is not None:
            self.counts.wasted_seconds += speculation.outcome.took

    def new_utterance(self) -> None:
        """The utterance ended or was dropped: the next one's texts are compared afresh."""
        self._last_text = None

    def adopt(self, job: RecognitionJob) -> Optional[Speculation]:
        """A closed utterance: the speculation on exactly its audio and engine becomes its
        recognition (its outcome may be there already); None when there is none (a speculation
        on other audio is dropped: that utterance comes first). An outcome already there finds
        the worker idle: a speculation starts only then, and any utterance closing before this
        one dropped it."""
        speculation = self.current
        if speculation is None or speculation.adopted is not None:
            return None
        if not speculation.is_for(job):
            self.drop()
            return None
        speculation.adopted = job
        if speculation.outcome is not None:
            self.current = None
            self.counts.used += 1
        return speculation

    def finished(
        self, speculation: Speculation, outcome: RecognitionOutcome, heard_complete: bool = True
    ) -> Optional[RecognitionJob]:
        """A speculation's recognition ended: the closed utterance whose result it is, or None
        (cancelled, or the utterance is still being collected). ``heard_complete``: whether the
        audio says the turn is complete too (turn_end_model; True without one)."""
        speculation.running = False
        if speculation.watchdog is not None:
            speculation.watchdog.cancel()
        if speculation.cancelled:
            self.counts.wasted_seconds += outcome.took
            return None
        speculation.outcome = outcome
        speculation.complete = heard_complete and self.text_complete(speculation, outcome)
        job = speculation.adopted
        if job is not None:
            self.current = None
            self.counts.used += 1
        return job

    def text_complete(self, speculation: Speculation, outcome: RecognitionOutcome) -> bool:
        """Whether a speculation's text is complete by itself (no comparison with the one before); with
        the audio alone deciding in free speech (turn_end_text false), any text."""
        text = speculated_text(outcome)
        if self._audio_alone and speculation.hears_turn_end:
            return bool(text.strip())
        return is_complete(text, None, speculation.grammar is not None, self._answers)

    def needs_the_audio(self, speculation: Speculation, outcome: RecognitionOutcome) -> bool:
        """Whether the turn-end model must hear the turn complete too: in free speech, where the text
        is complete but is not one of complete_answers (an answer the robot waits for ends the turn
        at once: the model scores a word said alone either way)."""
        if speculation.grammar is not None or not self.text_complete(speculation, outcome):
            return False
        return speculated_text(outcome).strip(" .?!").lower() not in self._answers

    def ends_turn(self, speculation: Speculation) -> bool:
        """Whether a finished speculation, not adopted, is a complete answer (remembered for the
        next one): with a grammar in force any text (every engine that takes a grammar answers
        with whole phrases of it, or nothing), else one of complete_answers or the same text as
        the speculation before it on this utterance."""
        if speculation.cancelled or speculation.adopted is not None or speculation.outcome is None:
            return False
        text = speculated_text(speculation.outcome)
        complete = is_complete(text, self._last_text, speculation.grammar is not None, self._answers)
        self._last_text = text.strip().lower()  # as is_complete compares it
        return complete

    def completed_on(self, samples: int) -> Optional[bool]:
        """Whether the finished speculation on the first ``samples`` is complete by itself; None
        when there is none (not finished, on other audio, or none at all)."""
        speculation = self.current
        if speculation is None or speculation.adopted is not None or speculation.outcome is None:
            return None
        return speculation.complete if speculation.samples == samples else None

    def running_for(self, job: RecognitionJob) -> bool:
        """Whether ``job``'s recognition is a speculation that runs now."""
        return self.current is not None and self.current.adopted is job and self.current.running


def speculated_text(outcome: RecognitionOutcome) -> str:
    """The text of a speculation's outcome; "" for a failed recognition."""
    transcript = proper_transcript(outcome.answer)
    return transcript.text if transcript is not None else ""


def decides_at_end_of_speech(
    recognizer: Recognizer, grammar: Optional[Grammar], chosen: bool, hears_turn_end: bool = False
) -> bool:
    """Whether a speculation with ``recognizer`` decides on the end of speech (end_of_turn.py).

    Left to its default (``chosen`` false): with a grammar in force, an engine that can be stopped
    (Whisper, NeMo). In free speech a pause after a closed sentence would split people's speech
    (behind the robot's gate 0.3 s split 4 of 18 recordings of people reading), and pocketsphinx's
    grammar takes a piece of speech cut at a pause for the nearest phrase (people reading "go
    forward ... ten meters", published "no"; waiting for the pause, nothing).
    end_of_speech set (``chosen``): with a grammar every engine; in free speech an engine that can
    be stopped. One that cannot (pocketsphinx) decides once an utterance (EndOfTurn's
    decides_once), and never in free speech: each decision runs it to its end on the whole
    utterance so far, and its text is never a closed sentence (it writes no punctuation), so the
    turn would end at the pause anyway; its free decoding of a command and a second of babble after
    it takes 2.1 s, and a decision at each end heard in it kept the text up to 15 s late
    (bench/figures/end_of_speech.py).
    ``hears_turn_end`` (the turn-end model hears with the engine in force: TurnEnd.hears): in
    free speech an engine that can be stopped decides too, the turn ending only where the audio
    says it is complete as well (SpeculationRules)."""
    stoppable = isinstance(recognizer, Stoppable)
    if grammar is not None:
        return stoppable or chosen
    return stoppable and (chosen or hears_turn_end)


def complete_answers(setting: str) -> FrozenSet[str]:
    """The complete_answers setting as a set of lower-case answers."""
    return frozenset(word.strip().lower() for word in setting.split(",") if word.strip())


# An engine that writes punctuation (Whisper, Parakeet) closes a sentence with one of these; a
# sentence it hears cut off it leaves open, or trails off with an ellipsis.
SENTENCE_ENDS = (".", "?", "!")
TRAILING_OFF = ("...", "\u2026")


def ends_sentence(text: str) -> bool:
    """Whether ``text`` ends with a closed sentence."""
    text = text.rstrip()
    return text.endswith(SENTENCE_ENDS) and not text.endswith(TRAILING_OFF)


def is_complete(text: str, previous: Optional[str], grammar_mode: bool, answers: FrozenSet[str]) -> bool:
    """Whether a speculation's text is a whole answer, so the turn may end early: in grammar mode
    any text (the engine only gives whole phrases of the grammar); otherwise a closed sentence,
    one of ``answers``, or the same text as the speculation before it on this utterance (more
    audio changed nothing)."""
    if ends_sentence(text) and text.strip(" .?!"):
        return True
    text = text.strip().lower()
    if not text:
        return False
    return grammar_mode or text in answers or text == previous
