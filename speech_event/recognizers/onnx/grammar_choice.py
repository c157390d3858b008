"""The grammar decision the neural engines share: which phrase was said, or none.

Each phrase of the grammar has its exact log-probability under the model (the engine scores it: a
forward algorithm, teacher forcing); the model's own free decoding of the same audio has its
log-probability too. The best phrase is the answer when the free text is that phrase, or when it
is at most ``threshold`` nats less likely than the free text (a log-likelihood ratio): speech
outside the grammar is far more likely as what was said than as any phrase, and is rejected with
the best phrase named. Not per second: one wrong word costs the same in a long phrase as in a
short one (measured on the tones models: about 9.4 nats a letter, whatever the phrase's length).
"""

import re
from dataclasses import dataclass
from typing import Dict, Optional

from speech_event.ports import Transcript

# Measured on the tones models of every family: a phrase said exactly scores 0 (its text is the
# free text), one letter off -9.4 to -10 nats; models of real speech are less sure of each token.
NEURAL_GRAMMAR_THRESHOLD = -5.0

_NOT_SPELT = re.compile(r"[^a-z' ]+")


def spelt(text: str) -> str:
    """``text`` as a grammar writes phrases: lower-case words of a-z and ', punctuation dropped."""
    return " ".join(_NOT_SPELT.sub(" ", text.lower()).split())


@dataclass(frozen=True)
class GrammarChoice:
    """The free decoding and the phrases' scores for one utterance."""

    free_text: str
    free_score: float  # log-probability of the free decoding
    phrase_scores: Dict[str, float]  # log-probability of each phrase (its best form)

    def ratio(self, phrase: str) -> float:
        """log P(phrase) - log P(free text), in nats."""
        return self.phrase_scores[phrase] - self.free_score

    def transcript(self, threshold: float, confidence: Optional[float] = None) -> Transcript:
        """The phrase said, or no text naming the best phrase as rejected."""
        said = spelt(self.free_text)
        if said in self.phrase_scores:
            return Transcript(said, confidence)
        best = max(self.phrase_scores, key=self.phrase_scores.__getitem__)
        if self.ratio(best) >= threshold:
            return Transcript(best, confidence)
        return Transcript("", rejected=best)
