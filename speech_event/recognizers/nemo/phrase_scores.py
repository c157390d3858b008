"""The exact log-probabilities of many token sequences (a grammar's phrases) under a transducer,
sharing the model's work on their common prefixes.

The joint's outputs after a prefix depend on the prefix only, so the sequences form a trie and each
trie node costs the decoder-joint once, over all frames; the nodes of one depth go in one call (in
chunks of at most MAX_ROWS rows). Of each node's outputs only the log-probabilities a forward pass
reads are kept (the blank's, its children's tokens', the durations'), not the whole vocabulary.
CTC needs no such sharing: ``ctc_log_likelihood`` on the model's log-probabilities, per sequence.
"""

from collections import defaultdict
from dataclasses import dataclass
from typing import Dict, List, Optional, Sequence, Set, Tuple

import numpy as np
import onnxruntime

from speech_event.recognizers.nemo.model import LstmState, TransducerModel
from speech_event.recognizers.nemo.rnnt import PAD, rnnt_moves, transducer_forwards
from speech_event.recognizers.nemo.tdt import tdt_moves
from speech_event.recognizers.onnx.hypothesis import log_softmax

# Decoder-joint rows (trie nodes x frames) per call: bounds the memory of one call.
MAX_ROWS = 4096

Prefix = Tuple[int, ...]


@dataclass(frozen=True)
class _Node:
    """One prefix's log-probabilities at every frame: what the forward passes of its sequences read."""

    blank: np.ndarray  # [T']
    next_tokens: Dict[int, np.ndarray]  # a child's token -> [T']
    durations: np.ndarray  # [T', len(durations)]; no columns for RNN-T


def rnnt_scores(
    model: TransducerModel,
    frames: np.ndarray,
    sequences: Sequence[Sequence[int]],
    blank: int,
    one_per_frame: bool = False,
    run: Optional[onnxruntime.RunOptions] = None,
) -> List[float]:
    """log P(sequence | audio) for each of ``sequences`` under an RNN-T model, as
    ``rnnt_log_likelihood`` gives it (``one_per_frame``: as ``rnnt_moves`` says); ``frames``
    [T', D] are the encoder's."""
    if not sequences:
        return []
    nodes = _trie_log_probabilities(model, frames, sequences, blank, 0, run)
    blank_lp, token_lp, _, lengths = _along(nodes, sequences, len(frames), 0)
    blank_moves, token_moves, past_end = rnnt_moves(blank_lp, token_lp, one_per_frame)
    return transducer_forwards(blank_moves, token_moves, lengths, past_end)


def tdt_scores(
    model: TransducerModel,
    frames: np.ndarray,
    sequences: Sequence[Sequence[int]],
    blank: int,
    durations: Sequence[int],
    past_end: bool = False,
    run: Optional[onnxruntime.RunOptions] = None,
) -> List[float]:
    """log P(sequence | audio) for each of ``sequences`` under a TDT model, as ``tdt_log_likelihood``
    gives it; ``frames`` [T', D] are the encoder's, ``durations`` as config.json lists them."""
    if not sequences:
        return []
    nodes = _trie_log_probabilities(model, frames, sequences, blank, len(durations), run)
    blank_lp, token_lp, duration_lp, lengths = _along(nodes, sequences, len(frames), len(durations))
    return transducer_forwards(*tdt_moves(blank_lp, token_lp, duration_lp, durations), lengths, past_end)


def _along(
    nodes: Dict[Prefix, _Node], sequences: Sequence[Sequence[int]], frames: int, duration_count: int
) -> Tuple[np.ndarray, np.ndarray, np.ndarray, List[int]]:
    """Along each of ``sequences``, in rows padded past its end with ``PAD`` as
    ``transducer_forwards`` takes them: the blank's log-probabilities [P, T', U + 1], the next
    token's [P, T', U] and the durations' [P, T', U + 1, duration_count]; and the lengths."""
    lengths = [len(sequence) for sequence in sequences]
    width = max(lengths) + 1
    blank = np.full((len(sequences), frames, width), PAD)
    token = np.full((len(sequences), frames, width - 1), PAD)
    duration = np.full((len(sequences), frames, width, duration_count), PAD)
    for row, sequence in enumerate(sequences):
        for u in range(len(sequence) + 1):
            node = nodes[tuple(sequence[:u])]
            blank[row, :, u] = node.blank
            duration[row, :, u] = node.durations
            if u < len(sequence):
                token[row, :, u] = node.next_tokens[sequence[u]]
    return blank, token, duration, lengths


def _trie_log_probabilities(
    model: TransducerModel,
    frames: np.ndarray,
    sequences: Sequence[Sequence[int]],
    blank: int,
    duration_count: int,
    run: Optional[onnxruntime.RunOptions],
) -> Dict[Prefix, _Node]:
    """Every prefix of ``sequences`` (the empty one included), by depth: the nodes of a depth feed
    their last token with their parent's state, as ``TransducerModel.lattice`` does for one sequence."""
    prefixes = {tuple(sequence[:u]) for sequence in sequences for u in range(len(sequence) + 1)}
    children: Dict[Prefix, Set[int]] = defaultdict(set)
    for sequence in sequences:
        for u, token in enumerate(sequence):
            children[tuple(sequence[:u])].add(token)
    nodes: Dict[Prefix, _Node] = {}
    # by prefix, the state its children's calls start from; the root's call, whose parent ()[:-1] is
    # itself, from the initial state
    states: Dict[Prefix, LstmState] = {(): model.initial_state()}
    per_call = max(1, MAX_ROWS // max(1, len(frames)))
    for depth in range(max((len(prefix) for prefix in prefixes), default=-1) + 1):
        level = sorted(prefix for prefix in prefixes if len(prefix) == depth)
        next_states: Dict[Prefix, LstmState] = {}
        for first in range(0, len(level), per_call):
            chunk = level[first : first + per_call]
            parents = [states[prefix[:-1]] for prefix in chunk]
            logits, after = model.joint(
                frames,
                [prefix[-1] if prefix else blank for prefix in chunk],
                (
                    np.concatenate([h for h, _ in parents], axis=1),
                    np.concatenate([c for _, c in parents], axis=1),
                ),
                run,
            )
            split = logits.shape[-1] - duration_count
            # the whole chunk at once: per node, numpy's call overhead was most of a phrase score
            tokens_lp = log_softmax(logits[:, :, :split])
            durations_lp = log_softmax(logits[:, :, split:]) if duration_count else tokens_lp[:, :, :0]
            for i, prefix in enumerate(chunk):
                token_lp = tokens_lp[i]
                nodes[prefix] = _Node(
                    blank=token_lp[:, blank],
                    next_tokens={token: token_lp[:, token] for token in children[prefix]},
                    durations=durations_lp[i],
                )
                next_states[prefix] = (after[0][:, i : i + 1], after[1][:, i : i + 1])
        states = next_states
    return nodes
