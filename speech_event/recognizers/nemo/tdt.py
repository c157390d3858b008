"""Greedy TDT (token-and-duration transducer) decoding, as NeMo's default greedy_batch does it.

The joint gives the token logits (blank last) followed by one logit per duration in
``durations`` (frames to move on). At frame t: the best token and the best duration; a blank
moves on by its duration, at least 1; a token is emitted (the prediction network's state moves on
with it) and time moves on by its duration, which may be 0: then the next token is sought on the
same frame, and after ``max_symbols`` tokens on one frame time moves on by 1.
"""

from typing import Sequence

import numpy as np

from speech_event.recognizers.nemo.rnnt import State, Step
from speech_event.recognizers.onnx.hypothesis import Hypothesis


def tdt_greedy(
    frames: np.ndarray,
    step: Step[State],
    state: State,
    blank: int,
    durations: Sequence[int],
    max_symbols: int,
) -> Hypothesis:
    """The hypothesis for ``frames`` [T', D]; ``durations`` as config.json lists them."""
    found = Hypothesis()
    last, time, on_this_frame = blank, 0, 0
    while time < len(frames):
        logits, next_state = step(frames[time], last, state)
        token_logits = logits[: len(logits) - len(durations)]
        token = int(np.argmax(token_logits))
        duration = int(durations[int(np.argmax(logits[len(token_logits) :]))])
        if token == blank:
            time, on_this_frame = time + max(duration, 1), 0
            continue
        found.emit(token, token_logits)
        last, state = token, next_state
        on_this_frame += 1
        if duration > 0 or on_this_frame >= max_symbols:
            time, on_this_frame = time + max(duration, 1), 0
    return found
