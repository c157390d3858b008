"""The model's vocabulary: one ``token id`` per line, the blank last (NeMo's export, vocab.txt).

SentencePiece marks a word's start with '▁'; it becomes a space. Control tokens such as ``<unk>``
or ``<blk>`` produce no text.
"""

import re
from pathlib import Path
from typing import Dict, List, Sequence

from speech_event.errors import ModelError

WORD_START = "\u2581"
_CONTROL = re.compile(r"^<[^<>]+>$")


class Vocabulary:
    """Token ids to text: SentencePiece pieces, the blank last, control tokens silent."""

    def __init__(self, pieces: Sequence[str]) -> None:
        self._pieces = list(pieces)

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
