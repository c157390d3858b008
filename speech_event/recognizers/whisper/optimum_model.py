"""A Whisper model as Hugging Face optimum exports it (``automatic-speech-recognition-with-past``),
run with onnxruntime.

``encoder_model.onnx``: ``input_features`` float32 [1, n_mels, 3000] -> ``last_hidden_state``.
``decoder_model_merged.onnx``: ``input_ids``, ``encoder_hidden_states``, for each block i
``past_key_values.i.decoder.key``/``.value`` (the self-attention cache) and
``past_key_values.i.encoder.key``/``.value`` (the cross-attention's), and ``use_cache_branch`` ->
``logits`` and the same caches as ``present.i...``. Without the cache (the prompt), it computes the
cross-attention's keys and values from the encoder's output, once; with it, one token a call: the
with-past graph is traced at one token, and several at once would attend without a causal mask.
Each file may have an int8 version (``encoder_model_int8.onnx``), which the ``quantization`` key picks.
"""

import copy
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np
import onnxruntime

from speech_event.errors import ModelError
from speech_event.recognizers.onnx.directory import CPU_FP32, Runtime
from speech_event.recognizers.onnx.session import check_tensors, last_dimension, open_session, providers
from speech_event.recognizers.whisper.optimum_layout import OPTIMUM_FILES

ENCODER_FILE = "encoder_model.onnx"
DECODER_FILE = "decoder_model_merged.onnx"
PAST, PRESENT = "past_key_values.", "present."
DECODER_INPUTS = {"input_ids": 2, "encoder_hidden_states": 3, "use_cache_branch": 1}
OPTIMUM_DIRECTORY = (
    f"a Whisper model of Hugging Face optimum's export holds {ENCODER_FILE}, {DECODER_FILE}, {OPTIMUM_FILES} "
    "(speech-event pull whisper-base DIR fetches one)"
)
EXPORTER = "optimum's automatic-speech-recognition-with-past export"


def _empty(cache: onnxruntime.NodeArg) -> np.ndarray:
    """An empty cache [0, heads, 0, width], of the heads and width the file fixes (onnxruntime
    checks fixed dimensions)."""
    return np.zeros(
        [size if axis in (1, 3) and isinstance(size, int) else 0 for axis, size in enumerate(cache.shape)],
        np.float32,
    )


class OptimumWhisperModel:
    """encoder_model.onnx and decoder_model_merged.onnx, their tensors checked at load."""

    def __init__(self, directory: Path, runtime: Runtime = CPU_FP32) -> None:
        execution_providers = providers(runtime.cuda)
        encoder_path = runtime.model_file(directory, ENCODER_FILE)
        decoder_path = runtime.model_file(directory, DECODER_FILE)
        self._encoder = open_session(encoder_path, execution_providers, OPTIMUM_DIRECTORY)
        self.decoder = open_session(decoder_path, execution_providers, OPTIMUM_DIRECTORY)
        check_tensors(encoder_path, "inputs", self._encoder.get_inputs(), {"input_features": 3}, EXPORTER)
        check_tensors(
            encoder_path, "outputs", self._encoder.get_outputs(), {"last_hidden_state": 3}, EXPORTER
        )
        pasts = [arg for arg in self.decoder.get_inputs() if arg.name.startswith(PAST)]
        if not pasts:
            raise ModelError(
                f"{decoder_path}: no {PAST}* inputs: a decoder without its cache; export with "
                "--task automatic-speech-recognition-with-past (optimum merges the decoders)"
            )
        caches = {arg.name: 4 for arg in pasts}
        check_tensors(
            decoder_path, "inputs", self.decoder.get_inputs(), {**DECODER_INPUTS, **caches}, EXPORTER
        )
        presents = {name.replace(PAST, PRESENT, 1): 4 for name in caches}
        check_tensors(
            decoder_path, "outputs", self.decoder.get_outputs(), {"logits": 3, **presents}, EXPORTER
        )
        self.caches = list(caches)
        self.presents = list(presents)
        # What the cache inputs get with the cache branch off, which reads none of them
        self.no_cache = {arg.name: _empty(arg) for arg in pasts}

    @property
    def vocabulary_size(self) -> Optional[int]:
        return last_dimension(self.decoder, "logits")

    def decoding(self, mel: np.ndarray, run: Optional[onnxruntime.RunOptions] = None) -> "OptimumDecoding":
        (hidden,) = self._encoder.run(
            ["last_hidden_state"], {"input_features": mel[None].astype(np.float32)}, run
        )
        return OptimumDecoding(self, np.asarray(hidden), run)


class OptimumDecoding:
    """One piece of audio's decoding with the merged decoder: the caches of the tokens given so far."""

    def __init__(
        self, model: OptimumWhisperModel, hidden: np.ndarray, run: Optional[onnxruntime.RunOptions] = None
    ) -> None:
        self._model = model
        self._hidden = hidden
        self._run = run
        self._cache: Optional[Dict[str, np.ndarray]] = None  # None: no token given yet

    def __call__(self, tokens: Sequence[int]) -> np.ndarray:
        """The logits [len(tokens), vocabulary] of the tokens after those given before."""
        if self._cache is None:
            return self._step(list(tokens), self._model.no_cache, use_cache=False)
        return np.concatenate([self._step([token], self._cache, use_cache=True) for token in tokens])

    def _step(self, tokens: List[int], cache: Dict[str, np.ndarray], use_cache: bool) -> np.ndarray:
        model = self._model
        inputs = {
            "input_ids": np.array([tokens], np.int64),
            "encoder_hidden_states": self._hidden,
            "use_cache_branch": np.array([use_cache]),
            **cache,
        }
        logits, *presents = model.decoder.run(["logits", *model.presents], inputs, self._run)
        new = dict(zip(model.caches, presents))
        # The cross-attention's keys and values come from the branch without the cache; the other
        # gives empty ones in their place.
        self._cache = (
            new
            if not use_cache
            else {name: new[name] if ".decoder." in name else cache[name] for name in model.caches}
        )
        return np.asarray(logits[0])

    def fork(self) -> "OptimumDecoding":
        """A decoding that goes on from the tokens given so far, apart from this one; a call replaces
        the cache's arrays, never writes into them, so the two share them until each runs on."""
        return copy.copy(self)
