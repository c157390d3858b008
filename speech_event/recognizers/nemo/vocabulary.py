"""The model's vocabulary: one ``token id`` per line, the blank last (NeMo's export, vocab.txt).

SentencePiece marks a word's start with '▁'; it becomes a space. Control tokens such as ``<unk>``
or ``<blk>`` produce no text. Text can be turned back to token ids (a grammar's phrases, to be
scored by the model), by longest pieces first.
"""

import re
from pathlib import Path
from typing import Dict, List, Optional, Sequence

from speech_event.errors import ModelError

WORD_START = "\u2581"
_CONTROL = re.compile(r"^<[^<>]+>$")


class Vocabulary:
    """Token ids to text: SentencePiece pieces, the blank last, control tokens silent."""

    def __init__(self, pieces: Sequence[str]) -> None:
        self._pieces = list(pieces)
        spelling = [(i, piece) for i, piece in enumerate(self._pieces) if not _CONTROL.match(piece)]
        # a word's first piece by its text after the mark (the bare mark: ""), and the inner pieces
        self._word_starts: Dict[str, int] = {}
        self._inner: Dict[str, int] = {}
        for i, piece in spelling:
            if piece.startswith(WORD_START):
                self._word_starts.setdefault(piece[len(WORD_START) :], i)
            else:
                self._inner.setdefault(piece, i)

    @property
    def size(self) -> int:
        """Tokens including the blank."""
        return len(self._pieces)

    @property
    def blank(self) -> int:
        return len(self._pieces) - 1

    def text(self, ids: Sequence[int]) -> str:
        pieces = (self._pieces[i] for i in ids)
        joined = "".join("" if _CONTROL.match(piece) else piece.replace(WORD_START, " ") for piece in pieces)
        return " ".join(joined.split())

    def encode(self, text: str) -> List[int]:
        """Token ids for ``text``: lower-cased, words split on spaces, each word a word-start piece
        ('▁' and the longest prefix that lets the rest be spelt) then the longest inner pieces.
        ModelError names a word the vocabulary cannot spell; control tokens are never used."""
        ids: List[int] = []
        for word in text.lower().split():
            spelt = self._spell(word)
            if spelt is None:
                raise ModelError(
                    f"the model's vocabulary has no pieces for the word {word!r}: it cannot be spelt "
                    f"as a word-start piece ({WORD_START}...) then inner pieces"
                )
            ids += spelt
        return ids

    def _spell(self, word: str) -> Optional[List[int]]:
        """Longest pieces first, a shorter one only where the longest leaves a rest no piece spells."""
        # spellable[i]: word[i:] is a sequence of inner pieces
        spellable = [False] * len(word) + [True]
        for i in reversed(range(len(word))):
            spellable[i] = any(word[i:j] in self._inner and spellable[j] for j in range(i + 1, len(word) + 1))
        start = next(
            (j for j in reversed(range(len(word) + 1)) if word[:j] in self._word_starts and spellable[j]),
            None,
        )
        if start is None:
            return None
        ids, i = [self._word_starts[word[:start]]], start
        while i < len(word):
            j = next(
                j for j in reversed(range(i + 1, len(word) + 1)) if word[i:j] in self._inner and spellable[j]
            )
            ids.append(self._inner[word[i:j]])
            i = j
        return ids


def load_vocabulary(path: Path) -> Vocabulary:
    """Read vocab.txt; ModelError names a line that is not ``token id``, or ids missing."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as problem:
        raise ModelError(f"{path}: cannot read the vocabulary: {problem.strerror}") from None
    by_id: Dict[int, str] = {}
    for number, line in enumerate(lines, start=1):
        piece, _, token_id = line.rpartition(" ")
        if not token_id.isdigit() or not piece:
            raise ModelError(f"{path}:{number}: expected 'token id', found {line!r}")
        by_id[int(token_id)] = piece
    if sorted(by_id) != list(range(len(by_id))):
        raise ModelError(f"{path}: token ids must be 0 to {len(by_id) - 1}, each once")
    pieces: List[str] = [by_id[i] for i in range(len(by_id))]
    return Vocabulary(pieces)
