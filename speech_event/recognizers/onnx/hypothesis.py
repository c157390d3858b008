"""What a greedy decoding found: the token ids and NeMo's hypothesis score.

The score is the sum, over the emitted tokens, of the token's log-probability (log-softmax over
the token logits, blank included; TDT's duration logits are not tokens). exp(score) is the
confidence NeMo reports, and so the robot's node.
"""

import math
from dataclasses import dataclass, field
from typing import List, Tuple

import numpy as np


@dataclass(eq=False)
class Hypothesis:
    """The tokens a greedy decoding emitted and their summed log-probability; ``confidence`` is its exp.

    A transducer emits a token per decoder-joint call (thousands in a long utterance): ``emit`` only
    keeps the token's logits row, and ``score`` log-softmaxes the rows kept so far in one array
    operation, not a handful of numpy calls per token in the decoding loop."""

    tokens: List[int] = field(default_factory=list)
    _summed: float = 0.0  # the log-probabilities added or scored so far
    _unscored: List[Tuple[int, np.ndarray]] = field(default_factory=list, repr=False)

    def emit(self, token: int, token_logits: np.ndarray) -> None:
        self.tokens.append(token)
        self._unscored.append((token, token_logits))

    def add(self, log_probability: float) -> None:
        """A log-probability of the path that is not an emitted token's (CTC's frames)."""
        self._summed += log_probability

    @property
    def score(self) -> float:
        if self._unscored:
            tokens, rows = zip(*self._unscored)
            scored = log_softmax(np.stack(rows))[np.arange(len(tokens)), list(tokens)]
            self._summed += float(scored.sum())
            self._unscored = []
        return self._summed

    @property
    def confidence(self) -> float:
        return math.exp(self.score)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Hypothesis):
            return NotImplemented
        return (self.tokens, self.score) == (other.tokens, other.score)


def log_softmax(logits: np.ndarray) -> np.ndarray:
    """log(softmax) over the last axis, in float64, each row shifted by its maximum so it cannot
    overflow: one row, or a lattice's or a decoding's rows at once."""
    values = np.asarray(logits, dtype=np.float64)
    shifted = values - values.max(axis=-1, keepdims=True)
    result: np.ndarray = shifted - np.log(np.exp(shifted).sum(axis=-1, keepdims=True))
    return result
