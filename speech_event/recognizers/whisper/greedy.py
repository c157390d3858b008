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
    """The text tokens greedy decoding sampled, and the no-speech probability (None: no such token)."""

    tokens: List[int]  # the sampled text tokens, eot not included
    no_speech_prob: Optional[float]


def whisper_greedy(step: Step, prompt: Sequence[int], manifest: WhisperManifest) -> WhisperResult:
    """Greedy decoding after ``prompt`` by Whisper's rules: the text tokens and the no-speech probability."""
    logits = step(prompt)
    no_speech: Optional[float] = None
    if manifest.no_speech is not None:
        no_speech = float(np.exp(log_softmax(logits[prompt.index(manifest.sot)])[manifest.no_speech]))
    suppress, at_start = list(manifest.suppress), list(manifest.suppress_at_start)
    tokens: List[int] = []
    for sampled in range(manifest.sample_len):
        if sampled > 0:
            logits = step(tokens[-1:])
        last = np.array(logits[-1], dtype=np.float32)
        if sampled == 0:
            last[at_start] = -np.inf
        last[suppress] = -np.inf
        token = int(np.argmax(last))
        if token == manifest.eot:
            break
        tokens.append(token)
        if len(prompt) + len(tokens) > manifest.text_context:
            break
    return WhisperResult(tokens, no_speech)
