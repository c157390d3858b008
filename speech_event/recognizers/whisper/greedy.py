"""Greedy decoding with Whisper's rules, as whisper.decode does it at temperature 0 without
timestamps: the prompt (sot, language, task, no timestamps) first; the no-speech probability from
the logits at sot; then at each step the suppressed tokens (and, at the first step, " " and eot)
are ruled out and the best token taken, until eot or ``sample_len`` tokens."""

from dataclasses import dataclass
from typing import Callable, List, Optional, Sequence

import numpy as np

from speech_event.recognizers.onnx.hypothesis import log_softmax
from speech_event.recognizers.whisper.manifest import WhisperManifest

# New tokens -> their logits [len(tokens), vocabulary]; the caller keeps the tokens before (the
# decoder's key/value cache), so each step costs one position, not the whole sequence.
Step = Callable[[Sequence[int]], np.ndarray]


@dataclass
class WhisperResult:
    """The text tokens greedy decoding sampled, the no-speech probability (None: no such token) and
    the score: the sum of the sampled tokens' log-probabilities under Whisper's rules (see
    ``whisper_greedy``), which a grammar's phrases, scored by teacher forcing, are compared with."""

    tokens: List[int]  # the sampled text tokens, eot not included
    no_speech_prob: Optional[float]
    score: float


def whisper_logits(logits: np.ndarray, first: bool, manifest: WhisperManifest) -> np.ndarray:
    """One position's logits with what Whisper's rules rule out there at -inf: the suppressed tokens,
    and at the first text position (``first``) also " " and eot. Whisper's logit filters act before
    its log-softmax, so the probabilities are those of the tokens left."""
    row = np.array(logits, dtype=np.float32)
    if first:
        row[list(manifest.suppress_at_start)] = -np.inf
    row[list(manifest.suppress)] = -np.inf
    return row


def whisper_greedy(
    step: Step, prompt: Sequence[int], manifest: WhisperManifest, prompted: Optional[np.ndarray] = None
) -> WhisperResult:
    """Greedy decoding after ``prompt`` by Whisper's rules: the text tokens, the no-speech probability
    and the score. The score sums the log-probability of each sampled token and, when decoding ended
    on eot, of that eot: log P(tokens, eot), what teacher forcing gives a phrase. Ended on
    ``sample_len`` tokens or the decoder's context, it has no eot term: log P(tokens) of an unfinished
    text, which a finished phrase of the same tokens cannot exceed.

    ``prompted``: the prompt's logits when ``step`` has been given the prompt already (a grammar's
    phrases are scored from the same pass)."""
    logits = step(prompt) if prompted is None else prompted
    no_speech: Optional[float] = None
    if manifest.no_speech is not None:
        no_speech = float(np.exp(log_softmax(logits[prompt.index(manifest.sot)])[manifest.no_speech]))
    tokens: List[int] = []
    score = 0.0
    for sampled in range(manifest.sample_len):
        if sampled > 0:
            logits = step(tokens[-1:])
        last = whisper_logits(logits[-1], sampled == 0, manifest)
        token = int(np.argmax(last))
        score += float(log_softmax(last)[token])
        if token == manifest.eot:
            break
        tokens.append(token)
        if len(prompt) + len(tokens) > manifest.text_context:
            break
    return WhisperResult(tokens, no_speech, score)
