"""A Whisper decoding that records the tokens of each decoder pass, its forks' passes too."""

from typing import List, Sequence

import numpy as np

from speech_event.recognizers.whisper.model import Decoding


class RecordedDecoding:
    """``decoding``, each pass's tokens appended to ``passes`` (shared with its forks)."""

    def __init__(self, decoding: Decoding, passes: List[List[int]]) -> None:
        self._decoding, self.passes = decoding, passes

    def __call__(self, tokens: Sequence[int]) -> np.ndarray:
        self.passes.append(list(tokens))
        return self._decoding(tokens)

    def fork(self) -> "RecordedDecoding":
        return RecordedDecoding(self._decoding.fork(), self.passes)
