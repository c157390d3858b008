"""Speculative recognition: the utterance so far, transcribed while the speaker pauses (issue 11).

When no block has come for ``speculation_gap`` and the recognition worker is idle (closed
utterances always come first), the node hands the audio collected so far to the worker. If the
pause then ends with no new block, the closed utterance *is* that audio, so the speculation's
result is its result: published at once, or as soon as the speculation ends, instead of being
recognized again from the start. A block that arrives first makes the speculation worthless: it
is cancelled (with the engine's ``cancel`` where it has one, onnxruntime's RunOptions.terminate)
and its engine time counted as wasted. A speculation never publishes by itself, so the node
publishes exactly the texts it would publish without speculating, never later.

An engine that cannot be stopped (pocketsphinx) speculates only when its run time, as measured on
recent recognitions, says the speculation ends before the utterance could close: before the pause
after the last block, and before the length limit could cut it (audio arriving in real time).
Then no closed utterance ever waits for a speculation that more audio made worthless.

Early end of turn (``early_pause``, opt-in) builds on it: a speculation whose text is a complete
answer lets the pause end after ``early_pause`` instead of ``speech_pause_period``.
"""

from collections import deque
from dataclasses import dataclass
from typing import Deque, Dict, FrozenSet, Optional, Tuple

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
        self.runs_on = False  # cancelled after it started, with an engine that cannot be stopped
        self.outcome: Optional[RecognitionOutcome] = None
        # The closed utterance this speculation turned out to be, while it still runs: the
        # speculation's end publishes it.
        self.adopted: Optional[RecognitionJob] = None
        self.watchdog: Optional[Timer] = None  # recognition_timeout, once adopted

    def is_for(self, samples: int, recognizer: Recognizer) -> bool:
        """Whether a closed utterance of ``samples`` samples, bound to ``recognizer``, is exactly the
        audio this speculation transcribes."""
        return not self.cancelled and self.samples == samples and self.recognizer is recognizer

    def cancel(self) -> bool:
        """Superseded: never run it, or stop it where the engine allows. True when it runs on to
        its end (it started, and its engine cannot be stopped): the worker is busy until then."""
        self.cancelled = True
        started = self.handle is not None and not self.handle.cancel()
        stop = getattr(self.recognizer, "cancel", None)
        if stop is None:
            self.runs_on = started
            return started
        if self.running:
            stop()
        return False


class RunTimes:
    """How long each engine took on its recent recognitions, to bound how long a speculation of a
    given length will take. Conservative both ways: an utterance at least as long as a recent one
    takes that one's time scaled up by length; a shorter one takes no less than it did."""

    KEPT = 20  # recent enough to forget a first, cold run; enough to catch a slow one

    def __init__(self) -> None:
        # Keyed by the engine's identity: engines are built once and kept (speech_event/engines.py).
        self._recent: Dict[int, Deque[Tuple[float, float]]] = {}

    def record(self, recognizer: Recognizer, audio_seconds: float, took: float) -> None:
        if audio_seconds > 0:
            self._recent.setdefault(id(recognizer), deque(maxlen=self.KEPT)).append((audio_seconds, took))

    def expected(self, recognizer: Recognizer, audio_seconds: float) -> Optional[float]:
        """Seconds a transcription of ``audio_seconds`` should take at most; None before any was timed."""
        recent = self._recent.get(id(recognizer))
        if not recent:
            return None
        return max(took * max(1.0, audio_seconds / seconds) for seconds, took in recent)


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
