"""The NeMo families (conformer-transducer, parakeet) on onnxruntime: features -> encoder ->
greedy decoding (RNN-T, TDT or CTC, as the directory's config.json says) -> vocabulary.

``stop`` stops a running ``transcribe`` from another thread (onnxruntime's RunOptions.terminate):
the node's recognition_timeout and speculative recognition use it.

With a grammar in force: the greedy decoding as always, then the exact log-probability of each
phrase and of the greedy tokens (the CTC, RNN-T or TDT forward algorithm over the same encoder
output, phrase_scores.py), the answer chosen as onnx/grammar_choice.py says; its confidence is the
phrase's probability.
"""

import functools
import math
from pathlib import Path
from typing import Dict, List, Optional, Union

import numpy as np
import onnxruntime

from speech_event.errors import GrammarError, ModelError
from speech_event.grammar import Grammar
from speech_event.ports import Transcript
from speech_event.recognizers.nemo.ctc import ctc_greedy, ctc_log_likelihood
from speech_event.recognizers.nemo.features import features
from speech_event.recognizers.nemo.manifest import CTC, MANIFEST_FILE, TDT, Manifest, load_manifest
from speech_event.recognizers.nemo.model import CtcModel, TransducerModel
from speech_event.recognizers.nemo.phrase_scores import rnnt_scores, tdt_scores
from speech_event.recognizers.nemo.rnnt import rnnt_greedy
from speech_event.recognizers.nemo.tdt import tdt_greedy
from speech_event.recognizers.nemo.vocabulary import Vocabulary, load_vocabulary
from speech_event.recognizers.onnx.compiled_grammars import CompiledGrammars
from speech_event.recognizers.onnx.directory import CPU_FP32, Runtime, exported_directory
from speech_event.recognizers.onnx.grammar_choice import NEURAL_GRAMMAR_THRESHOLD, GrammarChoice
from speech_event.recognizers.onnx.hypothesis import Hypothesis
from speech_event.recognizers.onnx.session import StoppableRuns

VOCABULARY_FILE = "vocab.txt"
# NeMo's transcribe() pads audio shorter than a second with silence, half before and half after
# (its pad_min_duration and pad_direction defaults): the same audio gives the same tokens only so.
PAD_MIN_SECONDS = 1.0
ENGINE = "the NeMo engine"


def padded_as_nemo_does(audio: np.ndarray, sample_rate: int) -> np.ndarray:
    """``audio`` padded with silence to a second, half before and half after, as NeMo's transcribe does."""
    missing = int(PAD_MIN_SECONDS * sample_rate) - audio.size
    if missing <= 0:
        return audio
    return np.pad(audio, (missing // 2, missing - missing // 2))


class NemoRecognizer:
    """The Recognizer port on an exported NeMo model directory (conformer-transducer, parakeet); Stoppable."""

    def __init__(
        self,
        model_directory: Union[str, Path],
        runtime: Runtime = CPU_FP32,
        grammar: Optional[Grammar] = None,
        grammar_threshold: Optional[float] = None,
    ) -> None:
        """``grammar_threshold``: see onnx/grammar_choice.py (the ``grammar_threshold`` key); None:
        NEURAL_GRAMMAR_THRESHOLD."""
        directory = exported_directory(model_directory, ".nemo", "export-nemo")
        self._manifest = load_manifest(directory / MANIFEST_FILE)
        self._vocabulary = load_vocabulary(directory / VOCABULARY_FILE)
        self._model: Union[CtcModel, TransducerModel] = (
            CtcModel(directory, runtime)
            if self._manifest.decoding == CTC
            else TransducerModel(directory, runtime)
        )
        _check_logits(directory, self._model.logits_size, self._vocabulary, self._manifest)
        self._runs = StoppableRuns()
        self._threshold = NEURAL_GRAMMAR_THRESHOLD if grammar_threshold is None else grammar_threshold
        self._grammars = CompiledGrammars(self._phrase_tokens)
        self._grammars.use(grammar)
        self._last_choice: Optional[GrammarChoice] = None

    @property
    def sample_rate(self) -> int:
        return self._manifest.features.sample_rate

    @property
    def last_choice(self) -> Optional[GrammarChoice]:
        """The grammar decision of the last transcribe within a grammar (its free text and every
        phrase's score: the ratio each was judged by); None after free speech."""
        return self._last_choice

    def check_grammar(self, grammar: Grammar) -> None:
        """Every phrase must be spelt by the model's vocabulary."""
        self._grammars.compiled(grammar)

    def use_grammar(self, grammar: Optional[Grammar]) -> None:
        self._grammars.use(grammar)

    def _phrase_tokens(self, grammar: Grammar) -> Dict[str, List[int]]:
        """Each phrase's tokens."""
        phrases = grammar.sentences(ENGINE)
        try:
            return {phrase: self._vocabulary.encode(phrase) for phrase in phrases}
        except ModelError as problem:
            raise GrammarError(f"{grammar.source}: {problem}") from None

    def _encoded(self, audio: np.ndarray, run: Optional[onnxruntime.RunOptions]) -> np.ndarray:
        """The encoder's frames [T', D] (a CTC model's log-probabilities [T', V + 1]) for 16 kHz ``audio``."""
        inputs = features(padded_as_nemo_does(audio, self.sample_rate), self._manifest.features)
        if isinstance(self._model, CtcModel):
            return self._model.logits(inputs, run)
        return self._model.encode(inputs, run)

    def _greedy(self, encoded: np.ndarray, run: Optional[onnxruntime.RunOptions]) -> Hypothesis:
        manifest, blank = self._manifest, self._vocabulary.blank
        if isinstance(self._model, CtcModel):
            return ctc_greedy(encoded, blank)
        step = functools.partial(self._model.step, run=run)
        state = self._model.initial_state()
        if manifest.decoding == TDT:
            return tdt_greedy(encoded, step, state, blank, manifest.durations, manifest.max_symbols_per_step)
        return rnnt_greedy(encoded, step, state, blank, manifest.max_symbols_per_step)

    def hypothesis(self, audio: np.ndarray, run: Optional[onnxruntime.RunOptions] = None) -> Hypothesis:
        """The greedy token ids and score for 16 kHz ``audio``, before the vocabulary turns them to text."""
        return self._greedy(self._encoded(audio, run), run)

    def transcribe(self, audio: np.ndarray) -> Transcript:
        run = self._runs.start()
        self._last_choice = None
        encoded = self._encoded(audio, run)
        found = self._greedy(encoded, run)
        grammar = self._grammars.in_force
        if grammar is None:
            return Transcript(self._vocabulary.text(found.tokens), found.confidence)
        return self._within(self._grammars.compiled(grammar), encoded, found, run)

    def _within(
        self,
        phrases: Dict[str, List[int]],
        encoded: np.ndarray,
        found: Hypothesis,
        run: onnxruntime.RunOptions,
    ) -> Transcript:
        """The phrase of the grammar said, or none: the greedy tokens and every phrase scored exactly."""
        scores = self.log_likelihoods(encoded, [found.tokens, *phrases.values()], run)
        choice = GrammarChoice(self._vocabulary.text(found.tokens), scores[0], dict(zip(phrases, scores[1:])))
        self._last_choice = choice
        answer = choice.transcript(self._threshold)
        if not answer.text:
            return answer
        return Transcript(answer.text, math.exp(choice.phrase_scores[answer.text]))

    def log_likelihoods(
        self, encoded: np.ndarray, sequences: List[List[int]], run: Optional[onnxruntime.RunOptions] = None
    ) -> List[float]:
        """log P(tokens | audio) of each token sequence, summed over every alignment."""
        blank, manifest = self._vocabulary.blank, self._manifest
        if isinstance(self._model, CtcModel):
            return [ctc_log_likelihood(encoded, tokens, blank) for tokens in sequences]
        # Paths end where greedy decoding stops (a TDT model may jump past the last frame; with one
        # token a frame, a token moves on a frame): the probability of the texts this engine gives.
        if manifest.decoding == TDT:
            return tdt_scores(self._model, encoded, sequences, blank, manifest.durations, True, run)
        one_per_frame = manifest.max_symbols_per_step == 1
        return rnnt_scores(self._model, encoded, sequences, blank, one_per_frame, run)

    def stop(self) -> None:
        """Stop the transcribe running now: its next onnxruntime call raises."""
        self._runs.stop()


def _check_logits(directory: Path, size: Optional[int], vocabulary: Vocabulary, manifest: Manifest) -> None:
    """The model's logits per step must be the vocabulary's tokens (and TDT's durations)."""
    expected = vocabulary.size + len(manifest.durations if manifest.decoding == TDT else ())
    if size is not None and size != expected:
        durations = f" and {len(manifest.durations)} durations" if manifest.decoding == TDT else ""
        raise ModelError(
            f"{directory}: the model gives {size} logits per step, but {VOCABULARY_FILE} has "
            f"{vocabulary.size} tokens (blank included){durations} in {MANIFEST_FILE}: "
            "the files are not of one export"
        )
