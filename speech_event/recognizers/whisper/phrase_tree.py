"""A grammar's forms scored along their prefix tree, exactly where a grammar decision needs it.

The forms of a grammar's phrases share the prompt and often their first tokens (" go to the
kitchen", " go to the bedroom", " go to the kitchen."). Each shared stretch runs once, in one
decoder call from its parent's key/value cache; a stretch with one way on runs to where the tree
branches, so its rows cost one call too (a call costs about 3 ms, a token in it 0.4: tiny.en int8,
2 cores). After each call the tree is searched best first: a prefix's log-probability bounds every
form below it (each later token's log-probability is at most 0), so a branch that cannot reach
``least`` nor beat the best form found costs no call: the first token's bound, taken as deep as
the tree has been run. The forms that may decide are then scored in one call each, as
forced.score_phrases scores them (STRETCH_MARGIN says why).
"""

import heapq
import itertools
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence, Set, Tuple

import numpy as np

from speech_event.recognizers.onnx.hypothesis import log_softmax
from speech_event.recognizers.whisper.forced import score_phrases
from speech_event.recognizers.whisper.greedy import whisper_logits
from speech_event.recognizers.whisper.manifest import WhisperManifest
from speech_event.recognizers.whisper.model import Decoding

# An int8 decoder quantizes each call's activations by their own range, so a form run in stretches
# scores a little otherwise than in one call (up to 0.27 nats, tiny.en int8 on bench.figures.grammar's
# sets). The tree prunes only this far under what may decide, and each form that may is scored
# again in one call of its own, as forced.score_phrases scores it: the decision sees the same
# scores whatever the tree's shape.
STRETCH_MARGIN = 0.5


@dataclass(eq=False)
class _Prefix:
    """A node of the tree: the tokens after the prompt up to it, and what was run of it."""

    depth: int  # tokens after the prompt, this one's included
    children: Dict[int, "_Prefix"] = field(default_factory=dict)
    ends: List[int] = field(default_factory=list)  # the sequences that end here
    # Once run: the log-probabilities of the next token under Whisper's rules, and the decoding
    # after this prefix, which its children go on from.
    next_token: Optional[np.ndarray] = None
    prefix: float = 0.0  # its log-probability
    decoding: Optional[Decoding] = None  # at the end of a stretch run, and the root

    def below(self) -> List[int]:
        """Every sequence that ends here or further down."""
        return [*self.ends, *(index for child in self.children.values() for index in child.below())]


def _tree(sequences: Sequence[Sequence[int]]) -> _Prefix:
    root = _Prefix(0)
    for index, tokens in enumerate(sequences):
        node = root
        for token in tokens:
            node = node.children.setdefault(token, _Prefix(node.depth + 1))
        node.ends.append(index)
    return root


def _stretch(node: _Prefix, token: int) -> Tuple[List[int], List[_Prefix]]:
    """The tokens from ``node``'s child ``token`` down to where the tree branches or ends, and
    their nodes: one decoder call runs them all."""
    tokens, nodes = [token], [node.children[token]]
    while len(nodes[-1].children) == 1:
        ((following, child),) = nodes[-1].children.items()
        tokens.append(following)
        nodes.append(child)
    return tokens, nodes


class _Search:
    """The tree searched best first: which prefixes wait to be run, and the scores so far."""

    def __init__(self, sequences: Sequence[Sequence[int]], manifest: WhisperManifest) -> None:
        self.root = _tree(sequences)
        self.scores = [-np.inf] * len(sequences)
        self.exact: Set[int] = set()  # the sequences scored to their end along the tree
        # those of them run in one call from the prompt, as forced.score_phrases runs them
        self.in_one_call: Set[int] = set()
        self.best = -np.inf
        self._eot = manifest.eot
        self._manifest = manifest
        # (minus the bound, the order pushed, the node run, its child's token, that child's bound):
        # ties are popped in the order pushed, so every run makes the same calls
        self.waiting: List[Tuple[float, int, _Prefix, int, float]] = []
        self._order = itertools.count()

    def ran(self, node: _Prefix, prefix: float) -> None:
        """``node`` (of log-probability ``prefix``) has been run: its sequences are scored, its
        children wait, every sequence below each bounded by it."""
        assert node.next_token is not None
        self._scored(node, prefix)
        for token, child in node.children.items():
            bound = prefix + float(node.next_token[token])
            for index in child.below():
                self.scores[index] = bound
            heapq.heappush(self.waiting, (-bound, next(self._order), node, token, bound))

    def run(self, node: _Prefix, token: int) -> None:
        """Run the stretch from ``node``'s child ``token`` in one call from ``node``'s decoding."""
        assert node.decoding is not None and node.next_token is not None
        tokens, nodes = _stretch(node, token)
        decoding = node.decoding.fork()
        logits = decoding(tokens)
        prefix = node.prefix
        for parent, child, token_here, row in zip([node, *nodes], nodes, tokens, logits):
            assert parent.next_token is not None
            prefix += float(parent.next_token[token_here])
            child.next_token = log_softmax(whisper_logits(row, False, self._manifest))
            child.prefix = prefix
            if child is not nodes[-1]:
                self._scored(child, prefix)  # its one child is in this stretch
        nodes[-1].decoding = decoding
        self.ran(nodes[-1], prefix)
        if node is self.root:
            self.in_one_call.update(nodes[-1].ends)  # those ending inside it ran in a longer call

    def _scored(self, node: _Prefix, prefix: float) -> None:
        assert node.next_token is not None
        for index in node.ends:
            self.scores[index] = prefix + float(node.next_token[self._eot])
            self.exact.add(index)
            self.best = max(self.best, self.scores[index])


def score_phrases_that_decide(
    session: Decoding,
    prompt: Sequence[int],
    sequences: Sequence[Sequence[int]],
    manifest: WhisperManifest,
    prompted: np.ndarray,
    least: float,
    always: Sequence[int] = (),
) -> List[float]:
    """Each sequence's ``forced.score_phrases``, exact for every sequence that scores ``least`` or
    more, for the best one, and for those at the indexes ``always``. Each other sequence gets its
    score along the tree, or the log-probability of its longest prefix that was run, under
    ``least`` and the best's score. ``session`` has run the prompt, whose logits are ``prompted``.
    An empty sequence is eot at the first position, which Whisper's rules rule out: -inf."""
    for tokens in sequences:
        if len(prompt) + len(tokens) > manifest.text_context:
            raise ValueError(
                f"{len(tokens)} tokens after a prompt of {len(prompt)} exceed the decoder's "
                f"{manifest.text_context} positions"
            )
    search = _Search(sequences, manifest)
    root = search.root
    root.decoding = session
    root.next_token = log_softmax(whisper_logits(prompted[-1], True, manifest))
    search.ran(root, 0.0)
    while search.waiting:
        _, _, node, token, bound = search.waiting[0]
        if bound < least - STRETCH_MARGIN and bound < search.best - 2 * STRETCH_MARGIN:
            break  # so is every bound after it
        heapq.heappop(search.waiting)
        search.run(node, token)
    scores = search.scores
    deciding = [
        index
        for index, score in enumerate(scores)
        if index not in search.in_one_call
        and (
            index in always
            or (
                index in search.exact
                and score >= min(least - STRETCH_MARGIN, search.best - 2 * STRETCH_MARGIN)
            )
        )
    ]
    for index, score in zip(
        deciding, score_phrases(session, prompt, [sequences[i] for i in deciding], manifest, prompted)
    ):
        scores[index] = score
    return scores
