"""Greedy RNN-T decoding.

For each encoder frame, ask the decoder-joint for the next token given the last emitted token and
the prediction network's state; emit it while it is not the blank, at most ``max_symbols`` times per
frame, updating the state only on emission; the blank moves on to the next frame.
"""

from typing import Callable, List, Tuple, TypeVar

import numpy as np

State = TypeVar("State")
# (encoder frame [D], last token, state) -> (logits [V + 1], state after that token)
Step = Callable[[np.ndarray, int, State], Tuple[np.ndarray, State]]


def greedy_decode(
    frames: np.ndarray, step: Step[State], state: State, blank: int, max_symbols: int
) -> List[int]:
    """Token ids for ``frames`` [T', D]; the first 'last token' is the blank, as in NeMo."""
    tokens: List[int] = []
    last = blank
    for frame in frames:
        for _ in range(max_symbols):
            logits, next_state = step(frame, last, state)
            token = int(np.argmax(logits))
            if token == blank:
                break
            tokens.append(token)
            last, state = token, next_state
    return tokens
