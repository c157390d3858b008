"""The NeMo conformer-transducer recognizer: features -> encoder -> greedy RNN-T -> vocabulary.

``cancel`` stops a running ``transcribe`` from another thread (onnxruntime's RunOptions.terminate):
the node's recognition_timeout uses it, so a hung recognition does not hold up the next one.
"""

import functools
from pathlib import Path
from typing import List, Optional, Union

import numpy as np
import onnxruntime

from speech_event.asr.errors import ModelError
from speech_event.asr.features import features
from speech_event.asr.greedy import greedy_decode
from speech_event.asr.manifest import MANIFEST_FILE, load_manifest
from speech_event.asr.model import TransducerModel
from speech_event.asr.vocabulary import load_vocabulary
from speech_event.ports import Transcript

VOCABULARY_FILE = "vocab.txt"


class NemoTransducerRecognizer:
    def __init__(self, model_directory: Union[str, Path], cuda: bool = False) -> None:
        directory = Path(model_directory)
        if directory.suffix == ".nemo":
            raise ModelError(
                f"{directory} is a .nemo archive, not an exported model directory: export it once with "
                f"'speech-event export-nemo {directory} OUT_DIR' (needs the 'export' extra: nemo_toolkit), "
                "then give OUT_DIR"
            )
        if not directory.is_dir():
            raise ModelError(f"{directory}: no such model directory")
        self._manifest = load_manifest(directory / MANIFEST_FILE)
        self._vocabulary = load_vocabulary(directory / VOCABULARY_FILE)
        self._model = TransducerModel(directory, cuda)
        self._run: Optional[onnxruntime.RunOptions] = None  # the options of the transcribe running now

    @property
    def sample_rate(self) -> int:
        return self._manifest.features.sample_rate

    def token_ids(self, audio: np.ndarray, run: Optional[onnxruntime.RunOptions] = None) -> List[int]:
        """The greedy token ids for 16 kHz ``audio``, before the vocabulary turns them to text."""
        inputs = features(audio, self._manifest.features)
        if inputs.shape[1] == 0:
            return []
        return greedy_decode(
            self._model.encode(inputs, run),
            functools.partial(self._model.step, run=run),
            self._model.initial_state(),
            self._vocabulary.blank,
            self._manifest.max_symbols_per_step,
        )

    def transcribe(self, audio: np.ndarray) -> Transcript:
        run = onnxruntime.RunOptions()
        self._run = run
        return Transcript(self._vocabulary.text(self.token_ids(audio, run)))

    def cancel(self) -> None:
        """Stop the transcribe running now: its next onnxruntime call raises."""
        run = self._run
        if run is not None:
            run.terminate = True
