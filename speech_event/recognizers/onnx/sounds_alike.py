"""Whether a free decoding sounds like a phrase: their English pronunciations, phone by phone.

A trained Whisper model writes a command it half-hears as words that sound like it: festival's ked
voice saying "tell me a joke" came out as "Tell me, Joke.", "play some music" as "Place a music"
(issue 32). Their words differ by more than one, their sounds by one phone in 9 and in 12. The phones
are the CMU pronouncing dictionary's, which pocketsphinx's wheel ships (a dependency of this
package: the embedded English engine's dictionary). A word it does not hold (a name, Kinyarwanda)
has no pronunciation here, and a text with such a word sounds like nothing.
"""

import itertools
from functools import lru_cache
from pathlib import Path
from typing import List, Tuple

Phones = Tuple[str, ...]

# A text's pronunciations are every choice of its words' variants ("the": DH AH or DH IY), the
# first ones in the dictionary's order: enough for a command, bounded for a long sentence.
_MOST_PRONUNCIATIONS = 32


def sounds_alike(heard: str, phrase: str, share: float) -> bool:
    """Whether ``heard`` is pronounced as ``phrase`` with at most ``share`` of the phrase's phones
    changed, added or dropped, its first and last phones kept (both spelt as a grammar spells them:
    lower case, words of a-z and '). The ends: a near miss says more before or after a command
    ("go to the kitchen now": 2 phones more than 11), a command misheard keeps its edges."""
    heard_ways = pronunciations(heard)  # once, not again for each of the phrase's
    return any(
        said[0] == way[0] and said[-1] == way[-1] and phone_edits(way, said) <= share * len(way)
        for way in pronunciations(phrase)
        for said in heard_ways
    )


def pronunciations(text: str) -> List[Phones]:
    """``text``'s pronunciations (none when a word is not in the dictionary)."""
    ways = [_word_pronunciations(word) for word in text.split()]
    if not ways or not all(ways):
        return []
    return [sum(choice, ()) for choice in itertools.islice(itertools.product(*ways), _MOST_PRONUNCIATIONS)]


def phone_edits(one: Phones, other: Phones) -> int:
    """The fewest phones changed, added or dropped to make ``one`` into ``other`` (Levenshtein)."""
    previous = list(range(len(other) + 1))
    for row, phone in enumerate(one, 1):
        current = [row]
        for column, other_phone in enumerate(other, 1):
            dropped, added, changed = previous[column] + 1, current[column - 1] + 1, previous[column - 1]
            current.append(min(dropped, added, changed + (phone != other_phone)))
        previous = current
    return previous[-1]


@lru_cache(maxsize=4096)
def _word_pronunciations(word: str) -> Tuple[Phones, ...]:
    """The dictionary's pronunciations of ``word``: its lines ``word PH ON ES`` and ``word(2) ...``."""
    text = _dictionary()
    found: List[Phones] = []
    for key in (f"\n{word} ", f"\n{word}("):
        start = text.find(key)
        while start != -1:
            end = text.find("\n", start + 1)
            entry = text[start + 1 : end if end != -1 else len(text)]
            found.append(tuple(entry.split()[1:]))
            start = text.find(key, start + 1)
    return tuple(found)


@lru_cache(maxsize=1)
def _dictionary() -> str:
    """pocketsphinx's English dictionary as one text (3.3 MB), each line after a newline: read once,
    and searched for the few words a grammar and a free decoding hold, not parsed whole (126 000
    words: 30 MB as a dict of tuples)."""
    import pocketsphinx

    path = Path(pocketsphinx.get_model_path()) / "en-us" / "cmudict-en-us.dict"
    return "\n" + path.read_text(encoding="utf-8")
