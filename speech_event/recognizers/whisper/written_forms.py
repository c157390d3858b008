"""The texts Whisper may write a grammar's phrase as: a phrase is scored in each (forced.py) and
judged by its best, since the model gives the same words in another surface form (no capital, no
final stop, no comma where it would write one) far less probability.

Two kinds: the forms of every utterance (``phrase_variants``: " go left", " Go left." ...), and,
for a phrase the free decoding is that phrase misheard, the phrase written as the free text is
(``phrase_as_written``): tiny.en wrote the cards recording of "eight of spades four of clubs seven
of hearts" as " Eight of spades, four of close, seven of hearts." (-1.9 nats), and the phrase
scores -8.4 nats against it without the commas, -3.9 with them (within the threshold).
"""

import re
from typing import List, NamedTuple, Optional

from speech_event.spelling import spelt

# A word of the free text: what comes before its letters or digits, they, and what comes after
_WRITTEN_WORD = re.compile(r"^(\W*)(.*?)(\W*)$", re.DOTALL)


def phrase_variants(phrase: str) -> List[str]:
    """The texts Whisper may write a phrase as, to score each: after a leading space (Whisper's text
    starts with one), the first letter lower and capital, each without and with a final "." (Whisper
    writes "go left" as " Go left."), duplicates left out, in that order. Words are parted by single
    spaces; a final "." given is taken as the one Whisper may add."""
    stem = " ".join(phrase.split()).rstrip(".")
    if not stem:
        raise ValueError(f"the phrase {phrase!r} has no words")
    forms = [f" {first}{stem[1:]}{end}" for first in (stem[0].lower(), stem[0].upper()) for end in ("", ".")]
    return list(dict.fromkeys(forms))


class WrittenWord(NamedTuple):
    """A word of the free text as a grammar spells it, and how it was written."""

    word: str
    written: str  # as the free text wrote it ("8", "Queen"); a number of several words: the word
    before: str  # punctuation written before it
    after: str  # and after it
    capital: bool  # written with a capital first letter


def written_words(text: str) -> List[WrittenWord]:
    """Each word of ``text`` as a grammar spells it (``spelt``: "10" is "ten"), with its
    writing, the punctuation written before and after it and whether it starts with a capital. A
    written word spelt as several ("25": "twenty five") gives the first its punctuation before and
    capital, the last its punctuation after, and each is written as itself. Punctuation between
    words (" - ") and inside one ("left-hand") is left out: a form need not be the free text's,
    only the phrase in its sentence's punctuation."""
    words: List[WrittenWord] = []
    for chunk in text.split():
        match = _WRITTEN_WORD.match(chunk)
        assert match is not None  # every string matches
        before, core, after = match.groups()
        each = spelt(core).split()
        for index, word in enumerate(each):
            first, last = index == 0, index == len(each) - 1
            words.append(
                WrittenWord(
                    word,
                    core if len(each) == 1 else word,
                    before if first else "",
                    after if last else "",
                    first and core[:1].isupper(),
                )
            )
    return words


def aligned(phrase: List[str], heard: List[str]) -> List[Optional[int]]:
    """For each word of ``phrase``, the index of the word of ``heard`` it stands for in a least-edits
    alignment (the same word or one heard in its place), None for a word not heard. Of alignments
    with as few edits, the one that pairs the last words: it is read back from the end."""
    rows, columns = len(phrase) + 1, len(heard) + 1
    edits = [[0] * columns for _ in range(rows)]
    for i in range(rows):
        for j in range(columns):
            if i == 0 or j == 0:
                edits[i][j] = i + j
            else:
                changed = edits[i - 1][j - 1] + (phrase[i - 1] != heard[j - 1])
                edits[i][j] = min(changed, edits[i - 1][j] + 1, edits[i][j - 1] + 1)
    pairs: List[Optional[int]] = [None] * len(phrase)
    i, j = len(phrase), len(heard)
    while i > 0 and j > 0:
        if edits[i][j] == edits[i - 1][j - 1] + (phrase[i - 1] != heard[j - 1]):
            pairs[i - 1] = j - 1
            i, j = i - 1, j - 1
        elif edits[i][j] == edits[i - 1][j] + 1:
            i -= 1
        else:
            j -= 1
    return pairs


def phrase_as_written(phrase: str, free_text: str) -> str:
    """``phrase`` written as Whisper wrote ``free_text``, after a leading space as Whisper writes:
    its first word takes the free text's opening punctuation and capital, its last word the closing
    punctuation, and each word between the punctuation and capital of the free word it stands for
    (``aligned``), a word not heard none; a word heard as said is written as the free text wrote it
    (a digit: "8"). " Eight of spades, four of close, seven of hearts." writes "eight of spades four
    of clubs seven of hearts" as " Eight of spades, four of clubs, seven of hearts."; " 8 of spades,
    4 of close, 7 of hearts." as " 8 of spades, 4 of clubs, 7 of hearts."."""
    words = phrase.split()
    heard = written_words(free_text)
    if not heard:
        return " " + " ".join(words)
    last = len(heard) - 1
    out = []
    for position, index in enumerate(aligned(words, [each.word for each in heard])):
        # whose opening and whose closing the word takes: the free text's own at the phrase's ends
        opens = 0 if position == 0 else None if index == 0 else index
        closes = last if position == len(words) - 1 else None if index == last else index
        word = words[position]
        if index is not None and heard[index].word == word:
            word = heard[index].written
        if opens is not None:
            opening = heard[opens]
            word = opening.before + (word[:1].upper() + word[1:] if opening.capital else word)
        out.append(word if closes is None else word + heard[closes].after)
    return " " + " ".join(out)
