"""The grammar decision the neural engines share: which phrase of the grammar was said, or none.

The engine gives its free decoding of the utterance (the text and its log-probability), each
phrase's log-probability (teacher forcing), and, where it can score a phrase with nothing said
(Whisper), the audio's evidence for a phrase: log P(phrase | audio) - log P(phrase | silence). A
phrase's ratio is its log-probability minus the free text's, in nats; the free text is compared as
the grammar spells it (spelling.spelt). NeMo gives no evidence. The rules, in the order they apply
(``GrammarChoice.transcript``; docs/grammar.md numbers them so too):

1. The free text is a phrase: that phrase.
2. Else the free text is a phrase misheard, the phrase's ratio at least ``threshold``: the most
   probable such phrase. Misheard, for a phrase of two words or more: one word changed, or at most
   SOUND_ALIKE_SHARE of its phones changed (sounds_alike.py); for a one-word phrase: one word
   pronounced exactly as it ("for" for four).
   A phrase rules 1 and 2 take is published only if its evidence, where the engine gives one, is
   at least HEARD_EVIDENCE; else nothing is, that phrase named as rejected.
3. Else the evidence may take a phrase (Whisper). The candidates: each phrase whose ratio is at
   least PREFERRED_SLACK (or ``threshold``, when that is stricter); and, when the free text is one
   word, the most probable phrase if it is one word too, its ratio at least ``threshold`` and
   UNAMBIGUOUS_GAP above every other phrase (the one-word candidate: "Bye!" for five). Only the
   most probable candidate may be published: when its evidence is at least ONE_WORD_EVIDENCE if
   it is the one-word candidate, EVIDENCE_THRESHOLD otherwise.
4. Otherwise nothing, the most probable phrase named as rejected.

Why each rule and constant, and the utterances that decided them: docs/decisions.md."""

import math
from dataclasses import dataclass, field
from typing import Dict, List, Mapping, Optional

from speech_event.ports import Transcript
from speech_event.recognizers.onnx.sounds_alike import sounds_alike
from speech_event.spelling import spelt

# The fitted constants, each with what it was measured on (nats, but the share); docs/decisions.md.
# Rule 2, a misheard phrase's least ratio: trained tiny.en in the four voices; the tones models (issue 32).
NEURAL_GRAMMAR_THRESHOLD = -5.0
# Rule 2, share of a phrase's phones a sound-alike may change: tiny.en and base, the four voices (issue 32).
SOUND_ALIKE_SHARE = 0.25
# Rules 1, 2: least evidence for what the words take: tiny.en int8, base int8; voices, people (issues 32, 43).
HEARD_EVIDENCE = 2.7
# Rule 3, a candidate's least ratio: int8 quantization's half nat, tiny.en in festival's kal (issue 32).
PREFERRED_SLACK = -0.5
# Rule 3, the one-word candidate's lead over the next: people's digits written as another word (issue 43).
UNAMBIGUOUS_GAP = 2.0
# Rule 3, a candidate's least evidence: tiny.en and base, the voices' commands and other speech (issue 32).
EVIDENCE_THRESHOLD = 8.0
# Rule 3, the one-word candidate's: people's digits and words, room noise, pink and babble (issue 43).
ONE_WORD_EVIDENCE = 7.0


@dataclass(frozen=True)
class GrammarChoice:
    """The free decoding and the phrases' scores for one utterance."""

    free_text: str
    free_score: float  # log-probability of the free decoding
    # log-probability of each phrase (its best form); an engine may give, for a phrase below
    # ``least_deciding_score`` and below the best phrase, an upper bound of it instead
    phrase_scores: Dict[str, float]
    # The evidence (its best form's) for the phrase ``taken_by_the_words``, or else for those
    # ``evidence_candidates`` names, where the engine can score a phrase with nothing said
    evidence: Mapping[str, float] = field(default_factory=dict)

    def transcript(self, threshold: float, confidence: Optional[float] = None) -> Transcript:
        """The phrase said, or no text naming the phrase rejected: the module's rules in order."""
        taken = self.taken_by_the_words(threshold)  # rules 1 and 2
        if taken is not None:
            if self.evidence.get(taken, math.inf) < HEARD_EVIDENCE:
                return Transcript("", rejected=taken)
            return Transcript(taken, confidence)
        candidates = self.evidence_candidates(threshold)  # rule 3
        if candidates:
            best = self._most_probable(candidates)
            one_word = best == self._one_word_candidate(threshold)
            if self.evidence.get(best, -math.inf) >= (ONE_WORD_EVIDENCE if one_word else EVIDENCE_THRESHOLD):
                return Transcript(best, confidence)
        return Transcript("", rejected=self._most_probable(list(self.phrase_scores)))  # rule 4

    def taken_by_the_words(self, threshold: float) -> Optional[str]:
        """Rules 1 and 2: the free text itself, or the most probable phrase it is a mishearing of at
        least ``threshold``; None when the words take none."""
        if self.free_phrase is not None:
            return self.free_phrase
        said = spelt(self.free_text)
        misheard = [
            phrase
            for phrase in self.phrase_scores
            if self.ratio(phrase) >= threshold and heard_as(said, phrase)
        ]
        return self._most_probable(misheard) if misheard else None

    @property
    def free_phrase(self) -> Optional[str]:
        """The phrase the free text is, spelt as the grammar spells it, or None."""
        said = spelt(self.free_text)
        return said if said in self.phrase_scores else None

    def evidence_candidates(self, threshold: float) -> List[str]:
        """Rule 3: the phrases whose evidence may decide (few or none: the engine scores only these
        unheard), in the grammar's order, the one-word candidate last."""
        least = max(threshold, PREFERRED_SLACK)
        candidates = [phrase for phrase in self.phrase_scores if self.ratio(phrase) >= least]
        word = self._one_word_candidate(threshold)
        return candidates if word is None or word in candidates else [*candidates, word]

    def _one_word_candidate(self, threshold: float) -> Optional[str]:
        """The one-word phrase a one-word free text may be another word for, or None."""
        ranked = sorted(self.phrase_scores, key=self.phrase_scores.__getitem__, reverse=True)
        if len(spelt(self.free_text).split()) != 1 or len(ranked[0].split()) != 1:
            return None
        runner_up = self.phrase_scores[ranked[1]] if len(ranked) > 1 else -math.inf
        if self.ratio(ranked[0]) < threshold or self.phrase_scores[ranked[0]] - runner_up < UNAMBIGUOUS_GAP:
            return None
        return ranked[0]

    def ratio(self, phrase: str) -> float:
        """log P(phrase) - log P(free text), in nats."""
        return self.phrase_scores[phrase] - self.free_score

    def _most_probable(self, phrases: List[str]) -> str:
        """The phrase of ``phrases`` with the highest score, the first of them on a tie."""
        return max(phrases, key=self.phrase_scores.__getitem__)


def heard_as(heard: str, phrase: str) -> bool:
    """Rule 2's mishearing: for a phrase of two words or more, one word changed or sounding alike;
    for a one-word phrase, one word pronounced exactly as it (a homophone: "for" for four, "too" for
    two). A one-word phrase heard as a word that sounds otherwise is another word."""
    if len(phrase.split()) == 1:
        return len(heard.split()) == 1 and sounds_alike(heard, phrase, share=0.0)
    return one_word_changed(heard, phrase) or sounds_alike(heard, phrase, share=SOUND_ALIKE_SHARE)


def one_word_changed(heard: str, phrase: str) -> bool:
    """Whether ``heard`` is ``phrase`` (two words or more) with exactly one of its words changed."""
    words, others = heard.split(), phrase.split()
    return len(words) == len(others) >= 2 and sum(a != b for a, b in zip(words, others)) == 1


def least_deciding_score(free_score: float, threshold: float) -> float:
    """The least phrase score that can change ``GrammarChoice.transcript``: a phrase below it is
    below ``threshold`` (neither misheard nor a candidate of rule 3) and more than UNAMBIGUOUS_GAP
    below any phrase that may be the one-word candidate, so an upper bound of its score below it
    decides as the score itself. The best phrase, named when none is taken, needs its exact score
    too. The engine scores exactly only the phrases at least this (Whisper: phrase_tree.py)."""
    return free_score + threshold - UNAMBIGUOUS_GAP
