"""Speculative recognition: the utterance so far, transcribed while the speaker pauses (issue 11).

When no block has come for ``speculation_gap`` and the recognition worker is idle (closed
utterances always come first), the node hands the audio collected so far to the worker. If the
pause then ends with no new block, the closed utterance *is* that audio, so the speculation's
result is its result: published at once, or as soon as the speculation ends, instead of being
recognized again from the start. A block that arrives first makes the speculation worthless: it
is cancelled (with the engine's ``cancel`` where it has one, onnxruntime's RunOptions.terminate)
and its engine time counted as wasted. A speculation never publishes by itself, so the node
publishes exactly the texts it would publish without speculating, never later.

Early end of turn (``early_pause``, opt-in) builds on it: a speculation whose text is a complete
answer lets the pause end after ``early_pause`` instead of ``speech_pause_period``.
"""

from dataclasses import dataclass
from typing import FrozenSet, Optional

from speech_event.ports import Cancellable, Recognizer, Timer
from speech_event.recognition_queue import RecognitionJob, RecognitionOutcome


@dataclass
class SpeculationCounts:
    started: int = 0
    used: int = 0  # their result was the closed utterance's
    wasted_seconds: float = 0.0  # engine time of speculations that more audio made worthless


class Speculation:
    """One speculation: the first ``samples`` of the utterance being collected, with one engine.

    Every field is read and written under the node's lock."""

    def __init__(self, samples: int, recognizer: Recognizer) -> None:
        self.samples = samples
        self.recognizer = recognizer
        self.handle: Optional[Cancellable] = None
        self.running = False
        self.cancelled = False
        self.outcome: Optional[RecognitionOutcome] = None
        # The closed utterance this speculation turned out to be, while it still runs: the
        # speculation's end publishes it.
        self.adopted: Optional[RecognitionJob] = None
        self.watchdog: Optional[Timer] = None  # recognition_timeout, once adopted

    def is_for(self, samples: int, recognizer: Recognizer) -> bool:
        """Whether a closed utterance of ``samples`` samples, bound to ``recognizer``, is exactly the
        audio this speculation transcribes."""
        return not self.cancelled and self.samples == samples and self.recognizer is recognizer

    def cancel(self) -> None:
        """Superseded: never run it, or stop it where the engine allows."""
        self.cancelled = True
        if self.handle is not None:
            self.handle.cancel()
        stop = getattr(self.recognizer, "cancel", None)
        if self.running and stop is not None:
            stop()


def complete_answers(setting: str) -> FrozenSet[str]:
    return frozenset(word.strip().lower() for word in setting.split(",") if word.strip())


def is_complete(text: str, previous: Optional[str], grammar_mode: bool, answers: FrozenSet[str]) -> bool:
    """Whether a speculation's text is a whole answer, so the turn may end early: in grammar mode
    any text (the engine only gives whole phrases of the grammar); otherwise one of ``answers``,
    or the same text as the speculation before it on this utterance (more audio changed nothing)."""
    text = text.strip().lower()
    if not text:
        return False
    return grammar_mode or text in answers or text == previous
