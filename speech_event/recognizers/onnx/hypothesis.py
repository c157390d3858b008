"""What a greedy decoding found: the token ids and NeMo's hypothesis score.

The score is the sum, over the emitted tokens, of the token's log-probability (log-softmax over
the token logits, blank included; TDT's duration logits are not tokens). exp(score) is the
confidence NeMo reports, and so the robot's node.
"""

import math
from dataclasses import dataclass, field
from typing import List

import numpy as np


@dataclass
class Hypothesis:
    """The tokens a greedy decoding emitted and their summed log-probability; ``confidence`` is its exp."""

    tokens: List[int] = field(default_factory=list)
    score: float = 0.0

    def emit(self, token: int, token_logits: np.ndarray) -> None:
        self.tokens.append(token)
        self.score += float(log_softmax(token_logits)[token])

    @property
    def confidence(self) -> float:
        return math.exp(self.score)


def log_softmax(logits: np.ndarray) -> np.ndarray:
    """log(softmax(logits)) in float64, shifted by the maximum so it cannot overflow."""
    values = np.asarray(logits, dtype=np.float64)
    shifted = values - values.max()
    result: np.ndarray = shifted - np.log(np.exp(shifted).sum())
    return result
