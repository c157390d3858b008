"""Whisper's tokenizer, encoding only: text to the tokens the model was trained on, as
openai-whisper's tiktoken encoding makes them.

A grammar's phrases are scored by the probability of their tokens (forced.py), and the model
gives a text spelt in other tokens than its tokenizer's far less: tiny.en writes " spades" as
" sp" + "ades", and " spa" + "des" costs 16 nats more, enough to reject a phrase that was said.

tiktoken's byte-level BPE needs no merges file: a token's rank is its id, and a pair of adjacent
parts merges when the pair's bytes are a token, the lowest rank first. Text is first cut into words
by GPT-2's pattern (`'s|'t|'re|'ve|'m|'ll|'d| ?\\p{L}+| ?\\p{N}+| ?[^\\s\\p{L}\\p{N}]+|\\s+(?!\\S)|\\s+`),
written here for Python's ``re``, which has no ``\\p{...}``; a word that is a token is that token.
"""

import re
import sys
import unicodedata
from functools import lru_cache
from typing import Dict, List, Pattern, Sequence

from speech_event.errors import ModelError

# Unicode's White_Space characters, the \s of tiktoken's regex (Python's \s also takes \x1c-\x1f),
# as the inside of a character class
WHITE_SPACE = "\t\n\x0b\x0c\r \x85\xa0\u1680\u2000-\u200a\u2028\u2029\u202f\u205f\u3000"


@lru_cache(maxsize=None)
def word_pattern() -> Pattern[str]:
    """GPT-2's pattern in ``re``: \\w is exactly the letters (L), the numbers (N) and "_", and \\d
    the decimal digits (Nd), so \\p{L} is \\w less \\d, "_" and the other numbers (No, Nl: "²", "Ⅻ"),
    and \\p{N} is \\d and those. Finding them reads every character once (0.12 s here)."""
    numerals = "".join(
        re.escape(character)
        for character in map(chr, range(sys.maxunicode + 1))
        if character.isnumeric() and unicodedata.category(character) in ("No", "Nl")
    )
    letters = rf"(?:(?![{numerals}])[^\W\d_])+"
    numbers = rf"[\d{numerals}]+"
    others = rf"(?:[^\w{WHITE_SPACE}]|_)+"
    spaces, then_a_space_or_the_end = f"[{WHITE_SPACE}]+", f"(?![^{WHITE_SPACE}])"
    contractions = "'s|'t|'re|'ve|'m|'ll|'d"
    return re.compile(
        rf"{contractions}| ?{letters}| ?{numbers}| ?{others}|{spaces}{then_a_space_or_the_end}|{spaces}"
    )


class WhisperTokenizer:
    """Encodes text as Whisper's tokenizer does, from each token's bytes (tokens.txt, vocab.json):
    the text tokens are those below ``text_tokens`` (eot, the first special token), so that no text
    ever spells a special token; a duplicate piece keeps its first id."""

    def __init__(self, pieces: Sequence[bytes], text_tokens: int) -> None:
        word_pattern()  # made when the engine loads, not when the Behaviour Controller sets a grammar
        self._ranks: Dict[bytes, int] = {}
        for token, piece in enumerate(pieces[:text_tokens]):
            if piece:
                self._ranks.setdefault(piece, token)

    def encode(self, text: str) -> List[int]:
        """``text``'s tokens; ModelError names a part of it that no text token is (a byte missing
        from a small vocabulary, a capital a model without capitals cannot write)."""
        tokens: List[int] = []
        for word in word_pattern().findall(text):
            data = word.encode("utf-8")
            for part in [data] if data in self._ranks else self._merged(data):
                if part not in self._ranks:
                    raise ModelError(f"the model's text tokens cannot spell {text!r}: no token is {part!r}")
                tokens.append(self._ranks[part])
        return tokens

    def _merged(self, data: bytes) -> List[bytes]:
        """tiktoken's byte-pair merge: from single bytes, the adjacent pair whose bytes are the
        lowest-ranked token merges (the leftmost of equals), until no pair is a token."""
        parts = [data[index : index + 1] for index in range(len(data))]
        while True:
            pairs = [
                (self._ranks[pair], index)
                for index, pair in enumerate(map(bytes.__add__, parts, parts[1:]))
                if pair in self._ranks
            ]
            if not pairs:
                return parts
            _, index = min(pairs)
            parts[index : index + 2] = [parts[index] + parts[index + 1]]
