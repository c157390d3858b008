"""The grammar decision the neural engines share: which phrase was said, or none.

Each phrase of the grammar has its exact log-probability under the model (the engine scores it: a
forward algorithm, teacher forcing); the model's own free decoding of the same audio has its
log-probability too. A phrase is the answer when the free text is that phrase; or when the free
text is that phrase misheard, and the phrase is at most ``threshold`` nats less likely than the free
text (a log-likelihood ratio). Misheard: one word heard otherwise ("bring me the red cop" for "bring
me the red cup"), or words that sound like the phrase, at most a quarter of its phones different
("place a music" for "play some music", sounds_alike.py); a one-word phrase, only a word pronounced
exactly as it ("for" for four: people's digits, issue 43).
Whisper adds one more way (``evidence``), when those take none: a phrase the model finds about as
probable as its own greedy text (at most PREFERRED_SLACK nats less, or ``threshold`` when that is
stricter), which the audio made far more probable than it is with nothing said (EVIDENCE_THRESHOLD
nats, the phrase scored against silence), is taken whatever the free text's words; so is a
one-word phrase the free text, one word too, may be another word for ("Bye!" for five), when it is
the most probable phrase by UNAMBIGUOUS_GAP, within ``threshold``, with ONE_WORD_EVIDENCE. Only
the most probable of these candidates may be taken: one the model finds less probable is never
published on its evidence (base int8 wrote a spoken "stop" under babble as " Stun.", "stop" 1.7
nats above it with +7.9, "stand up" 0.2 below with +8.9). Anything else is rejected, the most likely
phrase named.

A phrase the words take (the free text, or the phrase it is a mishearing of) is taken only if the
audio's evidence for it is at least HEARD_EVIDENCE, where the engine can score it unheard: Whisper
writes the text it expects with nothing said (" Thank you.") for sound it cannot make out, babble
under a word, and words near it (" See you." for a "six" under babble: "thank you" one word
away).

Why the one-word way (issue 43, recordings of people saying digits and single command words):
people's short words are often written as another word ("Bye!" for five, " full" for four, " Dump."
for stop), the said word 0.6 to 5.4 nats less probable than that; other words heard so had at most
+5.6 evidence for the nearest command, the said ones +6.0 to +10.9. A free text of more words than
the phrase is a near miss ("Don't stop." for stop: +8.2), never taken so.

Why no more (issue 32, measured with trained Whisper tiny.en and base through bench/figures/grammar.py):
the ratio alone let a third of everyday speech through as a command. A short phrase the model
favours ("thank you") scores within a few nats of the free decoding of any speech the model is
unsure of, and above it for speech it mishears badly (espeak's "follow the car", freely "fadl
macar": +6.2 nats): out-of-grammar speech reached -0.3 nats and above, commands heard slightly
wrong -0.1 to -3.8. What separates them is the words and their sounds: a command misheard is the
command with one word changed, or words that sound like it; a near miss is a command with a word
added or left out ("go to the kitchen later": 4 phones more than its 11) or other speech. A
one-word phrase heard as a word that sounds otherwise is another word ("stops", "dan's" for
"dance"): never taken by the words.

Why the evidence (issue 32, the same measurements): greedy decoding is not the model's most
probable text. In festival's kal voice tiny.en wrote "wave your hand" as " Wait, go ahead.", yet
scored "wave your hand" 0.2 nats above it (base: " Wait, Lord hand.", +2.7); base wrote "dance" as
" Danz." (-0.4). Other words, so the words reject them. The ratio alone cannot take them: a
phrase the model expects whatever is said scores above the free text of other speech too: "thank
you", which tiny.en and base give -4.4 nats with nothing said (the next command, "yes", -8.1),
scored up to 7 nats above the free text of espeak's sentences (" I forgot to m- I'm gonna go out
to home."). What parts them is how much the audio raised the phrase: log P(phrase | audio) -
log P(phrase | silence). "wave your hand" +16.5, "dance" +8.3; "thank you" over that sentence -3.2.
Of other speech, a phrase within PREFERRED_SLACK of the free text had at most +6.0 ("how are you"
for base's " Hello, I'm Daryl"), and the highest evidence at any ratio, +14.1, was a near miss
("go to the kitchen later": its command at -4.6 nats), which the slack keeps out."""

import math
from dataclasses import dataclass, field
from typing import Dict, List, Mapping, Optional

from speech_event.ports import Transcript
from speech_event.recognizers.onnx.sounds_alike import sounds_alike
from speech_event.spelling import spelt

# The least ratio of a phrase the free text is misheard from. Trained tiny.en: commands with a
# word misheard -0.1 to -3.8 nats (festival's and espeak's voices), heard as sound-alike words
# -2.9 to +2.0; the tones models of every family: one letter off -9.4 to -10.
NEURAL_GRAMMAR_THRESHOLD = -5.0
# A phrase about as probable as the free text: quantization alone moves a text's score by about half
# a nat (tiny.en's "wave your hand" in kal: +0.18 fp32, -0.31 int8). The nearest other speech with
# evidence: " Don't stop." (base int8, espeak) and "stop" at -1.15 nats, +8.2.
PREFERRED_SLACK = -0.5
# The least evidence (nats) for such a phrase: the commands it took through the node +8.3 and more,
# other speech within the slack at most +6.0.
EVIDENCE_THRESHOLD = 8.0
# The least evidence for a phrase the words take (the free text itself, or a phrase it is a mishearing
# of: " See you." for a "six" under babble, "thank you" at -0.4; misheard ones said +5.7 and more),
# where the engine can score it unheard (Whisper), between what sound the model could not make out
# gave and what the phrase said gave: tiny.en int8 wrote " Thank you." for babble 10 dB under a spoken
# "bird" (+0.1), base int8 for jackson's "two" alone (+2.1); "thank you" said in espeak's and
# festival's voices had +3.3 to +3.7 (base int8) and +3.6 to +4.0 (tiny.en int8), every other command
# said +5.6 and more.
HEARD_EVIDENCE = 2.7
# The least evidence for a one-word phrase a one-word free text may be (issue 43, people's digits
# and command words through the node, 0 to 1 s of room noise, pink and babble 10 dB under them):
# other words with the most probable command a candidate had at most +5.6 (" DONE" and no, pink
# 10 dB); words said and written as another word +6.0 to +10.9 (" Fix." for six, " Hero." for
# zero: base int8 +7.5 to +7.9).
ONE_WORD_EVIDENCE = 7.0
# How far a one-word phrase heard as another word must be above every other phrase for its evidence
# to count: the people's digits heard as another word had 3.0 nats and more over the next digit.
UNAMBIGUOUS_GAP = 2.0


@dataclass(frozen=True)
class GrammarChoice:
    """The free decoding and the phrases' scores for one utterance."""

    free_text: str
    free_score: float  # log-probability of the free decoding
    # log-probability of each phrase (its best form); an engine may give, for a phrase below
    # ``least_deciding_score`` and below the best phrase, an upper bound of it instead
    phrase_scores: Dict[str, float]
    # For the phrase ``taken_by_the_words``, or else those ``evidence_candidates`` names, when the
    # engine can score a phrase with nothing said (Whisper): log P(phrase | audio) - log P(phrase |
    # silence), its best form's.
    evidence: Mapping[str, float] = field(default_factory=dict)

    def ratio(self, phrase: str) -> float:
        """log P(phrase) - log P(free text), in nats."""
        return self.phrase_scores[phrase] - self.free_score

    def evidence_candidates(self, threshold: float) -> List[str]:
        """The phrases whose evidence may decide (few or none: the engine scores only these unheard):
        those about as probable as the free text (PREFERRED_SLACK, or ``threshold`` when that is
        stricter); and, when the free text is one word, the most probable phrase if it is one word
        too, at least ``threshold``, and UNAMBIGUOUS_GAP above every other phrase."""
        least = max(threshold, PREFERRED_SLACK)
        candidates = [phrase for phrase in self.phrase_scores if self.ratio(phrase) >= least]
        word = self._one_word_heard_as(threshold)
        return candidates if word is None or word in candidates else [*candidates, word]

    def _one_word_heard_as(self, threshold: float) -> Optional[str]:
        """The one-word phrase a one-word free text may be another word for, or None."""
        ranked = sorted(self.phrase_scores, key=self.phrase_scores.__getitem__, reverse=True)
        if len(spelt(self.free_text).split()) != 1 or len(ranked[0].split()) != 1:
            return None
        runner_up = self.phrase_scores[ranked[1]] if len(ranked) > 1 else -math.inf
        if self.ratio(ranked[0]) < threshold or self.phrase_scores[ranked[0]] - runner_up < UNAMBIGUOUS_GAP:
            return None
        return ranked[0]

    @property
    def free_phrase(self) -> Optional[str]:
        """The phrase the free text is, spelt as the grammar spells it, or None."""
        said = spelt(self.free_text)
        return said if said in self.phrase_scores else None

    def taken_by_the_words(self, threshold: float) -> Optional[str]:
        """The phrase the free text's words name: the free text itself, or the most probable
        phrase it is a mishearing of at least ``threshold``; None when they name none."""
        if self.free_phrase is not None:
            return self.free_phrase
        said = spelt(self.free_text)
        misheard = [
            phrase
            for phrase in self.phrase_scores
            if self.ratio(phrase) >= threshold and heard_as(said, phrase)
        ]
        return max(misheard, key=self.phrase_scores.__getitem__) if misheard else None

    def transcript(self, threshold: float, confidence: Optional[float] = None) -> Transcript:
        """The phrase said, or no text naming the most likely phrase as rejected."""
        taken = self.taken_by_the_words(threshold)
        if taken is not None:
            if self.evidence.get(taken, math.inf) < HEARD_EVIDENCE:
                return Transcript("", rejected=taken)  # what the model writes for unclear sound
            return Transcript(taken, confidence)
        candidates = self.evidence_candidates(threshold)
        if candidates:  # the most probable only: never a phrase the model finds less probable
            best = max(candidates, key=self.phrase_scores.__getitem__)
            least = ONE_WORD_EVIDENCE if best == self._one_word_heard_as(threshold) else EVIDENCE_THRESHOLD
            if self.evidence.get(best, -math.inf) >= least:
                return Transcript(best, confidence)
        return Transcript("", rejected=max(self.phrase_scores, key=self.phrase_scores.__getitem__))


def least_deciding_score(free_score: float, threshold: float) -> float:
    """The least phrase score that can change ``GrammarChoice.transcript``: a phrase below it is
    below ``threshold`` (neither misheard nor a candidate for the evidence) and more than
    UNAMBIGUOUS_GAP below any phrase that may be the one word's, so an upper bound of its score
    below it decides as the score itself. The best phrase, named when none is taken, needs its
    exact score too: scoring every phrase the model writes for a command costs 0.7 to 1 s
    (Whisper tiny.en, the robot's 32 commands), scoring those that can decide a few decoder calls."""
    return free_score + threshold - UNAMBIGUOUS_GAP


def heard_as(heard: str, phrase: str) -> bool:
    """Whether ``heard`` is ``phrase`` misheard: for two words or more, one word changed or sounding
    alike; for one word, one word pronounced exactly as it (a homophone: "for" for four, "too" for
    two). A one-word phrase heard as a word that sounds otherwise is another word."""
    if len(phrase.split()) == 1:
        return len(heard.split()) == 1 and sounds_alike(heard, phrase, share=0.0)
    return one_word_changed(heard, phrase) or sounds_alike(heard, phrase)


def one_word_changed(heard: str, phrase: str) -> bool:
    """Whether ``heard`` is ``phrase`` (two words or more) with exactly one of its words changed."""
    words, others = heard.split(), phrase.split()
    return len(words) == len(others) >= 2 and sum(a != b for a, b in zip(words, others)) == 1
