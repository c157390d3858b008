"""Greedy CTC decoding: the best token of each frame, repeats merged, blanks dropped (NeMo's
greedy CTC). The score sums the log-probability of each frame's best token, blanks and repeats
included, as NeMo's greedy CTC hypothesis does.

Also the exact log-likelihood of a given token sequence (the CTC forward algorithm over all
alignments), by which a grammar's phrases are scored."""

import math
from typing import Sequence

import numpy as np

from speech_event.recognizers.onnx.hypothesis import Hypothesis, log_softmax


def ctc_greedy(logits: np.ndarray, blank: int) -> Hypothesis:
    """``logits`` [T', V + 1] (log-probabilities or raw: each frame is log-softmaxed)."""
    found = Hypothesis()
    previous = blank
    for frame in logits:
        log_probabilities = log_softmax(frame)
        token = int(np.argmax(log_probabilities))
        found.add(float(log_probabilities[token]))
        if token != blank and token != previous:
            found.tokens.append(token)
        previous = token
    return found


def ctc_log_likelihood(logits: np.ndarray, tokens: Sequence[int], blank: int) -> float:
    """log P(tokens | audio) for ``logits`` [T', V + 1] (each frame log-softmaxed as ctc_greedy does):
    the sum over every frame labelling that merges repeats and drops blanks to ``tokens``, so that
    phrases compare by the model's own probability of them; -inf when none can (too few frames).

    The forward algorithm on ``tokens`` with a blank before, between and after them: state s at frame
    t comes from s, s - 1, or s - 2 when s - 1 is a blank between two different tokens.
    """
    if len(logits) == 0:  # the empty labelling, which spells only the empty sequence
        return 0.0 if not tokens else -math.inf
    states = [blank]
    for token in tokens:
        states += [token, blank]
    labels = np.asarray(states, dtype=np.intp)
    # s - 2 -> s skips the blank between two tokens, unless they are the same (a repeat would merge)
    skips = np.zeros(len(states), dtype=bool)
    skips[2:] = (labels[2:] != blank) & (labels[2:] != labels[:-2])
    alpha = np.full(len(states), -np.inf)
    for t, frame in enumerate(logits):
        emitted = log_softmax(frame)[labels]
        if t == 0:
            alpha[:2] = emitted[:2]
            continue
        into = alpha.copy()
        into[1:] = np.logaddexp(into[1:], alpha[:-1])
        into[2:] = np.where(skips[2:], np.logaddexp(into[2:], alpha[:-2]), into[2:])
        alpha = into + emitted
    return float(np.logaddexp.reduce(alpha[-2:]))
