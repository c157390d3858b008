"""Greedy CTC decoding: the best token of each frame, repeats merged, blanks dropped (NeMo's
greedy CTC). The score sums the log-probability of each frame's best token, blanks and repeats
included, as NeMo's greedy CTC hypothesis does."""

import numpy as np

from speech_event.recognizers.onnx.hypothesis import Hypothesis, log_softmax


def ctc_greedy(logits: np.ndarray, blank: int) -> Hypothesis:
    """``logits`` [T', V + 1] (log-probabilities or raw: each frame is log-softmaxed)."""
    found = Hypothesis()
    previous = blank
    for frame in logits:
        log_probabilities = log_softmax(frame)
        token = int(np.argmax(log_probabilities))
        found.score += float(log_probabilities[token])
        if token != blank and token != previous:
            found.tokens.append(token)
        previous = token
    return found
