"""The NeMo families (conformer-transducer, parakeet) on onnxruntime: features -> encoder ->
greedy decoding (RNN-T, TDT or CTC, as the directory's config.json says) -> vocabulary.

``stop`` stops a running ``transcribe`` from another thread (onnxruntime's RunOptions.terminate):
the node's recognition_timeout and speculative recognition use it.
"""

import functools
from pathlib import Path
from typing import Optional, Union

import numpy as np
import onnxruntime

from speech_event.errors import ModelError
from speech_event.ports import Transcript
from speech_event.recognizers.nemo.ctc import ctc_greedy
from speech_event.recognizers.nemo.features import features
from speech_event.recognizers.nemo.manifest import CTC, MANIFEST_FILE, TDT, Manifest, load_manifest
from speech_event.recognizers.nemo.model import CtcModel, TransducerModel
from speech_event.recognizers.nemo.rnnt import rnnt_greedy
from speech_event.recognizers.nemo.tdt import tdt_greedy
from speech_event.recognizers.nemo.vocabulary import Vocabulary, load_vocabulary
from speech_event.recognizers.onnx.directory import exported_directory
from speech_event.recognizers.onnx.hypothesis import Hypothesis
from speech_event.recognizers.onnx.session import StoppableRuns

VOCABULARY_FILE = "vocab.txt"
# NeMo's transcribe() pads audio shorter than a second with silence, half before and half after
# (its pad_min_duration and pad_direction defaults): the same audio gives the same tokens only so.
PAD_MIN_SECONDS = 1.0


def padded_as_nemo_does(audio: np.ndarray, sample_rate: int) -> np.ndarray:
    """``audio`` padded with silence to a second, half before and half after, as NeMo's transcribe does."""
    missing = int(PAD_MIN_SECONDS * sample_rate) - audio.size
    if missing <= 0:
        return audio
    return np.pad(audio, (missing // 2, missing - missing // 2))


class NemoRecognizer:
    """The Recognizer port on an exported NeMo model directory (conformer-transducer, parakeet); Stoppable."""

    def __init__(self, model_directory: Union[str, Path], cuda: bool = False) -> None:
        directory = exported_directory(model_directory, ".nemo", "export-nemo")
        self._manifest = load_manifest(directory / MANIFEST_FILE)
        self._vocabulary = load_vocabulary(directory / VOCABULARY_FILE)
        self._model: Union[CtcModel, TransducerModel] = (
            CtcModel(directory, cuda) if self._manifest.decoding == CTC else TransducerModel(directory, cuda)
        )
        _check_logits(directory, self._model.logits_size, self._vocabulary, self._manifest)
        self._runs = StoppableRuns()

    @property
    def sample_rate(self) -> int:
        return self._manifest.features.sample_rate

    def hypothesis(self, audio: np.ndarray, run: Optional[onnxruntime.RunOptions] = None) -> Hypothesis:
        """The greedy token ids and score for 16 kHz ``audio``, before the vocabulary turns them to text."""
        inputs = features(padded_as_nemo_does(audio, self.sample_rate), self._manifest.features)
        manifest, blank = self._manifest, self._vocabulary.blank
        if isinstance(self._model, CtcModel):
            return ctc_greedy(self._model.logits(inputs, run), blank)
        frames = self._model.encode(inputs, run)
        step = functools.partial(self._model.step, run=run)
        state = self._model.initial_state()
        if manifest.decoding == TDT:
            return tdt_greedy(frames, step, state, blank, manifest.durations, manifest.max_symbols_per_step)
        return rnnt_greedy(frames, step, state, blank, manifest.max_symbols_per_step)

    def transcribe(self, audio: np.ndarray) -> Transcript:
        run = self._runs.start()
        found = self.hypothesis(audio, run)
        return Transcript(self._vocabulary.text(found.tokens), found.confidence)

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
