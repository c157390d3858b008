"""Greedy RNN-T decoding.

For each encoder frame, ask the decoder-joint for the next token given the last emitted token and
the prediction network's state; emit it while it is not the blank, at most ``max_symbols`` times per
frame, updating the state only on emission; the blank moves on to the next frame.
"""

from typing import Callable, Tuple, TypeVar

import numpy as np

from speech_event.recognizers.onnx.hypothesis import Hypothesis

State = TypeVar("State")
# (encoder frame [D], last token, state) -> (logits, state after that token)
Step = Callable[[np.ndarray, int, State], Tuple[np.ndarray, State]]


def rnnt_greedy(
    frames: np.ndarray, step: Step[State], state: State, blank: int, max_symbols: int
) -> Hypothesis:
    """The hypothesis for ``frames`` [T', D]; the first 'last token' is the blank, as in NeMo."""
    found = Hypothesis()
    last = blank
    for frame in frames:
        for _ in range(max_symbols):
            logits, next_state = step(frame, last, state)
            token = int(np.argmax(logits))
            if token == blank:
                break
            found.emit(token, logits)
            last, state = token, next_state
    return found
