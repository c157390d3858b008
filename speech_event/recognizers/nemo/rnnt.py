"""Greedy RNN-T decoding.

For each encoder frame, ask the decoder-joint for the next token given the last emitted token and
the prediction network's state; emit it while it is not the blank, at most ``max_symbols`` times per
frame, updating the state only on emission; the blank moves on to the next frame.

Also the exact log-likelihood of a given token sequence (the forward algorithm over all alignments),
which TDT shares: a grammar's phrases are scored by it.
"""

import math
from typing import Callable, Dict, List, Sequence, Tuple, TypeVar

import numpy as np

from speech_event.recognizers.onnx.hypothesis import Hypothesis, log_softmax

State = TypeVar("State")
# (encoder frame [D], last token, state) -> (logits, state after that token)
Step = Callable[[np.ndarray, int, State], Tuple[np.ndarray, State]]
# A move's frames on -> its log-probability at every (t, u): see ``transducer_forward``.
Moves = Dict[int, np.ndarray]
# What ``transducer_forwards`` takes past a shorter sequence's end: a log-probability finite (so
# that the running sums of the stay-on-frame moves never meet inf - inf) and so low that nothing
# it reaches counts.
PAD = -1e30


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


def blank_and_token_log_probabilities(
    log_probabilities: np.ndarray, tokens: Sequence[int], blank: int
) -> Tuple[np.ndarray, np.ndarray]:
    """From a lattice's token log-probabilities [T', U + 1, V + 1]: the blank's at every (t, u)
    [T', U + 1], and the next token's, ``tokens[u]``, at every (t, u < U) [T', U]."""
    positions = np.arange(len(tokens))
    emitted = log_probabilities[:, positions, np.asarray(tokens, dtype=np.intp)]
    return log_probabilities[:, :, blank], emitted


def transducer_forward(blank_moves: Moves, token_moves: Moves, past_end: bool = False) -> float:
    """log of the summed probability of every path from (t, u) = (0, 0) that ends by a blank
    landing exactly on t = T' with u = U, in log space; with ``past_end``, of every path whose last
    move, a blank or the last token, reaches or passes t = T' with u = U (where greedy decoding
    stops: its distribution over texts).

    ``blank_moves[d]`` [T', U + 1]: log-probability of a blank at (t, u) moving to (t + d, u), d >= 1;
    ``token_moves[d]`` [T', U]: of the next token at (t, u) moving to (t + d, u + 1), d >= 0.
    RNN-T is {1: blank} and {0: token}; TDT has one move per duration.
    """
    tokens = next(iter(blank_moves.values())).shape[-1] - 1 if blank_moves else 0
    batch = (
        {d: weights[None] for d, weights in blank_moves.items()},
        {d: w[None] for d, w in token_moves.items()},
    )
    return transducer_forwards(*batch, [tokens], past_end)[0]


def transducer_forwards(
    blank_moves: Moves, token_moves: Moves, lengths: Sequence[int], past_end: bool = False
) -> List[float]:
    """``transducer_forward`` of many token sequences at once (a grammar's phrases), each
    ``lengths[p]`` tokens long: ``blank_moves[d]`` [P, T', U + 1], ``token_moves[d]`` [P, T', U] with U
    the longest length, sequence p in row p and ``PAD`` past its end (cells no path of it reads).

    alpha(t, u) sums every way into (t, u); a d = 0 token move stays on frame t, so u runs upwards
    within each frame. Each sequence's figure is exactly what it gives alone: the same operations,
    in the same order, on its cells.
    """
    if not blank_moves:  # no blank moves on: no path can end
        return [-math.inf] * len(lengths)
    count, frames, positions = next(iter(blank_moves.values())).shape
    alpha = np.full((count, frames, positions), -np.inf)
    for t in range(frames):
        into = np.full((count, positions), -np.inf)
        if t == 0:
            into[:, 0] = 0.0
        for d, weights in blank_moves.items():
            if d <= t:
                into = np.logaddexp(into, alpha[:, t - d] + weights[:, t - d])
        for d, weights in token_moves.items():
            if 0 < d <= t:
                into[:, 1:] = np.logaddexp(into[:, 1:], alpha[:, t - d, :-1] + weights[:, t - d])
        if 0 in token_moves:
            # into[u] = logaddexp(into[u], into[u - 1] + staying[u - 1]) upwards in u is, unrolled,
            # the log-sum over j <= u of into[j] plus the staying moves from j to u: a running
            # log-sum-exp over prefix sums, in numpy, not a Python step per u.
            prefix = np.concatenate((np.zeros((count, 1)), np.cumsum(token_moves[0][:, t], axis=1)), axis=1)
            into = prefix + np.logaddexp.accumulate(into - prefix, axis=1)
        alpha[:, t] = into
    rows, last = np.arange(count), np.asarray(lengths, dtype=np.intp)
    if past_end:
        endings = [
            alpha[rows, t, last] + weights[rows, t, last]
            for d, weights in blank_moves.items()
            for t in range(max(0, frames - d), frames)
        ]
        before_last = np.maximum(last - 1, 0)
        endings += [
            np.where(last > 0, alpha[rows, t, before_last] + weights[rows, t, before_last], -np.inf)
            for d, weights in token_moves.items()
            if d > 0 and positions > 1
            for t in range(max(0, frames - d), frames)
        ]
    else:
        endings = [
            alpha[rows, frames - d, last] + weights[rows, frames - d, last]
            for d, weights in blank_moves.items()
            if d <= frames
        ]
    if not endings:
        return [-math.inf] * count
    return [float(score) for score in np.logaddexp.reduce(np.stack(endings), axis=0)]


def rnnt_moves(
    blank: np.ndarray, token: np.ndarray, one_per_frame: bool = False
) -> Tuple[Moves, Moves, bool]:
    """``transducer_forward``'s moves and ``past_end`` for RNN-T, from the blank's log-probabilities
    [..., T', U + 1] and the next token's [..., T', U]: a blank moves one frame on, a token stays on
    its frame. ``one_per_frame``: the decoding of max_symbols_per_step = 1, where a token moves one
    frame on too (greedy takes no blank after it) and a path ends on reaching T'."""
    if one_per_frame:
        return {1: blank}, {1: token}, True
    return {1: blank}, {0: token}, False


def rnnt_forward(blank: np.ndarray, token: np.ndarray, one_per_frame: bool = False) -> float:
    """log P(tokens) from the blank's log-probabilities [T', U + 1] and the next token's [T', U]
    (see ``rnnt_moves``)."""
    return transducer_forward(*rnnt_moves(blank, token, one_per_frame))


def rnnt_log_likelihood(lattice: np.ndarray, tokens: Sequence[int], blank: int) -> float:
    """log P(tokens | audio): the sum over every alignment, not greedy's one path, so that phrases
    compare by the model's own probability of them.

    ``lattice`` [T', U + 1, V + 1]: raw joint logits, lattice[t, u] at frame t after the prediction
    network consumed the start (the blank) and ``tokens[:u]``. alpha(0, 0) = 0; alpha(t, u) =
    logaddexp(alpha(t-1, u) + blank(t-1, u), alpha(t, u-1) + token(t, u-1)); the result is
    alpha(T'-1, U) + blank(T'-1, U), -inf with no frames.
    """
    return rnnt_forward(*blank_and_token_log_probabilities(log_softmax(lattice), tokens, blank))
