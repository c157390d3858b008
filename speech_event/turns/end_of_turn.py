"""End of turn at the end of speech (``end_of_speech``, issue 44): the turn ends where the speech
ended, as soon as the text up to there is complete, not ``speech_pause_period`` after the last block.

Where: ``end_of_speech`` seconds of non-speech heard after the speech in the samples
(speech_end.py), cut a little after its last frame; or no block for that long (soundDetection's
gate sends blocks only while it hears speech), cut after the last block. Whether: a speculation
transcribes the utterance up to the cut, and the turn ends there when its text is complete (a
phrase of the grammar in force; in free speech a sentence the engine closes or one of
``complete_answers``: speculation.py). The speculation starts as soon as the audio up to the cut
is there, before the end is heard (with the gate, at ``speculation_gap`` after the last block, on
the whole utterance), so its text is often ready when the decision comes; more blocks cancel it
only when they move the cut (speech goes on). What follows the cut begins the next utterance:
the room after the speech, which is not transcribed unless speech follows (worth_transcribing),
or a quiet word after the pause that the detector did not take for speech.

While a decision is pending, the blocks that arrive are held, in order with their arrival times,
and taken when it is made: the turn ends where the audio says, whether the engine decides in 50 ms
or in 2 s. The pause that ends the utterance waits for the decision too. So the same audio arriving
at the same times gives the same utterances and the same texts, at any load.
"""

from dataclasses import dataclass
from typing import Callable, List, Optional

import numpy as np

from speech_event.config import SpeechEventConfig, end_of_speech_seconds, ends_at_end_of_speech
from speech_event.turns.speech_end import SpeechEnds


@dataclass(frozen=True)
class HeldBlock:
    """A block that arrived while a decision was pending."""

    samples: np.ndarray
    arrival: float


class EndOfTurn:
    """The decisions on the utterance being collected, and the blocks held meanwhile. Every method
    is called under the node's lock."""

    def __init__(
        self,
        config: SpeechEventConfig,
        decides: Callable[[], bool] = lambda: True,
        decides_once: Callable[[], bool] = lambda: False,
    ) -> None:
        """``decides``: whether the engine and grammar in use now decide on the end of speech
        (speculation.decides_at_end_of_speech); while they do not, no cut is offered and the turn
        ends at the pause, as with end_of_speech off. ``decides_once``: whether the engine in use
        is one that cannot be stopped (pocketsphinx), which decides once an utterance. Each
        decision is a decoding of the whole utterance so far that runs to its end, and under
        babble an end is heard again and again: deciding each, a rejection came up to 9 s later
        than at the pause (bench/figures/end_of_speech.py)."""
        self.on = ends_at_end_of_speech(config)
        hangover = end_of_speech_seconds(config) or config.speech_pause_period
        self._ends = SpeechEnds(config.sample_rate, hangover)
        self.deciding: Optional[int] = None  # the cut being decided: samples of the utterance
        self._decided = 0  # the last cut decided on this utterance: no cut is decided twice
        self._held: List[HeldBlock] = []
        self.close_waits = False  # the pause ended while a decision was pending
        self._after_cut = False  # the utterance being collected follows a cut at the end of speech
        self._decides = decides
        self._decides_once = decides_once

    def heard(self, samples: np.ndarray) -> None:
        """The utterance being collected took these samples."""
        if self.on:
            self._ends.add(samples)

    def cut_at_length(self, rest: np.ndarray) -> None:
        """The utterance was cut at the length limit; ``rest`` begins the next (the speech goes on)."""
        self._decided = 0
        if self.on:
            self._ends.restart(rest, keep_level=True)

    def heard_end(self) -> Optional[int]:
        """A cut to decide, heard in the samples: end_of_speech of non-speech follows the speech."""
        return self._new(self._ends.heard_end() if self.on else None)

    def speculation_cut(self, paused: bool = False) -> Optional[int]:
        """Where a speculation may transcribe up to before the end is heard, so its text is there
        when the decision comes: the speech's end once its pad is taken, or once no block came
        for speculation_gap (``paused``), where a decision on that pause would cut (gap_end);
        None while speech goes on."""
        if not self.on or self.deciding is not None:
            return self.deciding
        if self._no_more_decisions():
            return None
        cut = self._after_last_block() if paused else self._ends.padded_end()
        return cut if cut is not None and cut > self._decided else None

    def gap_end(self) -> Optional[int]:
        """A cut to decide when no block came for end_of_speech: after the last block, if speech
        was heard."""
        return self._new(self._after_last_block() if self.on else None)

    def _after_last_block(self) -> Optional[int]:
        return self._ends.samples if self._ends.heard_speech() else None

    def _new(self, cut: Optional[int]) -> Optional[int]:
        if cut is None or self.deciding is not None or cut <= self._decided or self._no_more_decisions():
            return None
        return cut

    def _no_more_decisions(self) -> bool:
        """While the engine and grammar in use do not decide; with an engine that decides once,
        once a cut of this utterance was decided on (it went on)."""
        return not self._decides() or (self._decided > 0 and self._decides_once())

    def decide(self, cut: int) -> None:
        """A speculation on the utterance's first ``cut`` samples decides whether the turn ends."""
        self.deciding = self._decided = cut

    def hold(self, samples: np.ndarray, arrival: float) -> None:
        """A block that arrived while deciding: taken once the decision is made."""
        self._held.append(HeldBlock(samples, arrival))

    def decided(self) -> List[HeldBlock]:
        """The decision is made: the blocks held meanwhile, to take in order."""
        self.deciding, self.close_waits = None, False
        held, self._held = self._held, []
        return held

    def closed(self, at_cut: bool) -> None:
        """The utterance ended (``at_cut``: at the end of its speech); the next starts afresh."""
        self._after_cut, self._decided = at_cut, 0
        if self.on:
            self._ends.restart(np.zeros(0, dtype=np.float32), keep_level=at_cut)

    def dropped(self) -> None:
        """The utterance and the blocks held are thrown away (the node is disabled or stops)."""
        self.decided()
        self.closed(at_cut=False)

    def worth_speculating(self) -> bool:
        """Whether a speculation on the utterance so far can serve what the node publishes (issue 58):
        not on audio that a pause would throw away (worth_transcribing), nor, where the engine and
        grammar in force decide on the end of speech, before any speech is heard in it: no decision
        is made on such audio, so a speculation's text would serve only if the pause ended the
        utterance as it is, and the block that comes first (most often, the speech) makes it
        worthless. Without it the closed utterance is recognized as without speculation."""
        if not self.on or self._ends.heard_speech():
            return True
        return not (self._after_cut or self._decides())

    def worth_transcribing(self) -> bool:
        """Whether the utterance ending now is transcribed: not when it follows a cut at the end of
        speech and no speech was heard in it (the room after the speaker stopped)."""
        return not (self.on and self._after_cut and not self._ends.heard_speech())
