"""Greedy TDT (token-and-duration transducer) decoding, as NeMo's default greedy_batch does it.

The joint gives the token logits (blank last) followed by one logit per duration in
``durations`` (frames to move on). At frame t: the best token and the best duration; a blank
moves on by its duration, at least 1; a token is emitted (the prediction network's state moves on
with it) and time moves on by its duration, which may be 0: then the next token is sought on the
same frame, and after ``max_symbols`` tokens on one frame time moves on by 1.

Also the exact log-likelihood of a given token sequence under the TDT model (all alignments summed).
"""

from typing import Sequence, Tuple

import numpy as np

from speech_event.recognizers.nemo.rnnt import (
    Moves,
    State,
    Step,
    blank_and_token_log_probabilities,
    transducer_forward,
)
from speech_event.recognizers.onnx.hypothesis import Hypothesis, log_softmax


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


def tdt_moves(
    blank: np.ndarray, token: np.ndarray, duration: np.ndarray, durations: Sequence[int]
) -> Tuple[Moves, Moves]:
    """``transducer_forward``'s moves for TDT, from the blank's log-probabilities [..., T', U + 1],
    the next token's [..., T', U] and the durations' [..., T', U + 1, len(durations)]: each move is a
    token or blank and a duration."""
    blank_moves = {d: blank + duration[..., i] for i, d in enumerate(durations) if d > 0}
    token_moves = {d: token + duration[..., :-1, i] for i, d in enumerate(durations)}
    return blank_moves, token_moves


def tdt_forward(
    blank: np.ndarray,
    token: np.ndarray,
    duration: np.ndarray,
    durations: Sequence[int],
    past_end: bool = False,
) -> float:
    """log P(tokens) from the blank's log-probabilities [T', U + 1], the next token's [T', U] and
    the durations' [T', U + 1, len(durations)] (see ``tdt_moves``). ``past_end``: paths end where
    greedy decoding stops, on reaching or passing T' (see ``transducer_forward``), not only on a
    blank landing exactly on T' as in NeMo's loss."""
    return transducer_forward(*tdt_moves(blank, token, duration, durations), past_end)


def tdt_log_likelihood(
    lattice: np.ndarray, tokens: Sequence[int], blank: int, durations: Sequence[int], past_end: bool = False
) -> float:
    """log P(tokens | audio) summed over every TDT alignment, as NeMo's TDT loss defines it (its
    TDTLossPytorch and numba kernels): so phrases compare by the model's own probability of them.

    ``lattice`` [T', U + 1, V + 1 + len(durations)]: the joint's raw outputs at frame t after the
    prediction network consumed the start and ``tokens[:u]``, token logits then duration logits, each
    part log-softmaxed on its own. A move from (t, u) with t < T' is the next token, to (t + d, u + 1),
    d any duration (0 stays on the frame), or the blank, to (t + d, u), d >= 1 (a blank must move on);
    both pay the token's and the duration's log-probability at (t, u). A path counts when it ends with
    a blank landing exactly on t = T' with all U tokens emitted; a move landing past T', or a token
    landing on T', ends no path. -inf when no path can (e.g. durations too long for T'). With
    ``past_end``, a path ends with any move that reaches or passes T' with all U tokens emitted,
    where greedy decoding stops.
    """
    split = lattice.shape[-1] - len(durations)
    blank_lp, token_lp = blank_and_token_log_probabilities(log_softmax(lattice[..., :split]), tokens, blank)
    return tdt_forward(blank_lp, token_lp, log_softmax(lattice[..., split:]), durations, past_end)
