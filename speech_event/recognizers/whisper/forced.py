"""Scoring a grammar's phrases by teacher forcing: a phrase's exact log-probability under the model,
log P(its tokens, then eot | prompt, audio), by Whisper's decoding rules as ``whisper_greedy``
applies them, so that it compares with the score of the model's own greedy text (``WhisperResult``).

A phrase's forms (written_forms.py) are tokenized as Whisper's tokenizer does (tokenizer.py): the
model gives the same text in other tokens far less probability. The prompt's decoder pass is
shared: it runs once, then each phrase's tokens run in one decoder call from a fork of the
prompt's key/value cache.

``UnheardScores`` scores the same way against silence: what the model gives a text with nothing
said, against which the audio's evidence for a phrase is measured (onnx/grammar_choice.py).
"""

from typing import List, Optional, Sequence, Tuple

import numpy as np

from speech_event.recognizers.onnx.hypothesis import log_softmax
from speech_event.recognizers.whisper.features import SAMPLE_RATE, whisper_log_mel
from speech_event.recognizers.whisper.greedy import whisper_logits
from speech_event.recognizers.whisper.manifest import WhisperManifest
from speech_event.recognizers.whisper.model import Decoding, WhisperOnnx


def forced_log_likelihood(logits: np.ndarray, tokens: Sequence[int], manifest: WhisperManifest) -> float:
    """log P(tokens, then eot) from ``logits`` [len(tokens) + 1, vocabulary]: row i the decoder's
    logits before the i-th of tokens + [eot] (row 0: those of the prompt's last position). Each row
    is masked as ``whisper_greedy`` masks it before its log-softmax; -inf when a token is masked."""
    targets = [*tokens, manifest.eot]
    if len(logits) != len(targets):
        raise ValueError(f"{len(logits)} rows of logits for {len(targets)} tokens (eot included)")
    return sum(
        float(log_softmax(whisper_logits(row, position == 0, manifest))[target])
        for position, (row, target) in enumerate(zip(logits, targets))
    )


def score_phrases(
    session: Decoding,
    prompt: Sequence[int],
    sequences: Sequence[Sequence[int]],
    manifest: WhisperManifest,
    prompted: Optional[np.ndarray] = None,
) -> List[float]:
    """Each token sequence's ``forced_log_likelihood`` after ``prompt`` in the audio's decoding
    ``session``: one decoder pass for the prompt, then one per non-empty sequence, all its tokens
    from a fork of the prompt's cache. An empty sequence is eot at the first position, which
    Whisper's rules rule out: -inf. ``session`` is given no token yet, or, with ``prompted`` (the
    prompt's logits), the prompt alone."""
    after_prompt = (session(prompt) if prompted is None else prompted)[-1:]
    scores: List[float] = []
    for tokens in sequences:
        if len(prompt) + len(tokens) > manifest.text_context:
            raise ValueError(
                f"{len(tokens)} tokens after a prompt of {len(prompt)} exceed the decoder's "
                f"{manifest.text_context} positions"
            )
        logits = np.concatenate([after_prompt, session.fork()(tokens)]) if tokens else after_prompt
        scores.append(forced_log_likelihood(logits, tokens, manifest))
    return scores


class UnheardScores:
    """Token sequences' ``forced_log_likelihood`` after ``prompt`` with silence for audio: the
    model's prior for a text, high for what it expects when nothing is said (tiny.en writes " you"
    for silence and gives "thank you" -4.4 nats). The silence is encoded, and the prompt run over
    it, once (Whisper pads every piece to 30 s with zeros: a second of zeros is its empty window):
    0.35 to 1.1 s for tiny.en and base, once in the engine's life, when ``prepare`` is called (the
    engine checks a grammar: before any command is said) or else at the first call that has a
    sequence to score; free speech never pays it. Each sequence then costs one decoder call. Those
    calls are not stoppable (the caller checks its run after them)."""

    def __init__(self, model: WhisperOnnx, prompt: Sequence[int], manifest: WhisperManifest) -> None:
        self._model = model
        self._prompt = list(prompt)
        self._manifest = manifest
        self._silence: Optional[Tuple[Decoding, np.ndarray]] = None

    def prepare(self) -> Tuple[Decoding, np.ndarray]:
        """The silence encoded and the prompt run over it, now unless done before. Two threads may
        both do it (a grammar checked while a recognition scores): the same values either way."""
        if self._silence is None:
            silence = whisper_log_mel(np.zeros(SAMPLE_RATE, np.float32), self._manifest.mel_bands)
            decoding = self._model.decoding(silence)
            self._silence = decoding, decoding(self._prompt)
        return self._silence

    def __call__(self, sequences: Sequence[Sequence[int]]) -> List[float]:
        if not sequences:
            return []
        decoding, prompted = self.prepare()
        return score_phrases(decoding, self._prompt, sequences, self._manifest, prompted)
