"""The two ONNX files of speech-event export-whisper, run with onnxruntime.

``encoder.onnx``: ``mel`` float32 [1, n_mels, 3000] -> ``cross_k``, ``cross_v`` [layers, 1,
audio positions, width] (each decoder block's cross-attention keys and values, computed once).
``decoder.onnx``: ``tokens`` int64 [1, n], ``self_k``, ``self_v`` [layers, 1, past, width] (the
self-attention cache of the tokens before), ``cross_k``, ``cross_v`` -> ``logits`` [1, n, vocabulary],
``new_self_k``, ``new_self_v`` [layers, 1, past + n, width]: decoding is linear, not quadratic.
"""

from pathlib import Path
from typing import Optional, Sequence, Tuple

import numpy as np
import onnxruntime

from speech_event.asr.onnx_session import check_tensors, open_session, providers

ENCODER_FILE = "encoder.onnx"
DECODER_FILE = "decoder.onnx"
ENCODER_INPUTS = {"mel": 3}
ENCODER_OUTPUTS = {"cross_k": 4, "cross_v": 4}
DECODER_INPUTS = {"tokens": 2, "self_k": 4, "self_v": 4, "cross_k": 4, "cross_v": 4}
DECODER_OUTPUTS = {"logits": 3, "new_self_k": 4, "new_self_v": 4}
WHISPER_DIRECTORY = (
    f"a Whisper model directory holds {ENCODER_FILE}, {DECODER_FILE}, tokens.txt and config.json "
    "(speech-event export-whisper CHECKPOINT DIR writes one)"
)
EXPORTER = "speech-event export-whisper"


class WhisperModel:
    def __init__(self, directory: Path, cuda: bool) -> None:
        execution_providers = providers(cuda)
        encoder_path, decoder_path = directory / ENCODER_FILE, directory / DECODER_FILE
        self._encoder = open_session(encoder_path, execution_providers, WHISPER_DIRECTORY)
        self._decoder = open_session(decoder_path, execution_providers, WHISPER_DIRECTORY)
        check_tensors(encoder_path, "inputs", self._encoder.get_inputs(), ENCODER_INPUTS, EXPORTER)
        check_tensors(encoder_path, "outputs", self._encoder.get_outputs(), ENCODER_OUTPUTS, EXPORTER)
        check_tensors(decoder_path, "inputs", self._decoder.get_inputs(), DECODER_INPUTS, EXPORTER)
        check_tensors(decoder_path, "outputs", self._decoder.get_outputs(), DECODER_OUTPUTS, EXPORTER)

    @property
    def vocabulary_size(self) -> Optional[int]:
        size = self._decoder.get_outputs()[0].shape[-1]
        return size if isinstance(size, int) else None

    def encode(
        self, mel: np.ndarray, run: Optional[onnxruntime.RunOptions] = None
    ) -> Tuple[np.ndarray, np.ndarray]:
        cross_k, cross_v = self._encoder.run(
            ["cross_k", "cross_v"], {"mel": mel[None].astype(np.float32)}, run
        )
        return np.asarray(cross_k), np.asarray(cross_v)


class DecoderSession:
    """One utterance's decoding: the cross-attention of its audio and the growing self-attention cache."""

    def __init__(
        self,
        model: WhisperModel,
        cross: Tuple[np.ndarray, np.ndarray],
        run: Optional[onnxruntime.RunOptions] = None,
    ) -> None:
        self._decoder = model._decoder
        self._cross_k, self._cross_v = cross
        layers, _, _, width = self._cross_k.shape
        self._self_k = self._self_v = np.zeros((layers, 1, 0, width), np.float32)
        self._run = run

    def __call__(self, tokens: Sequence[int]) -> np.ndarray:
        """The logits [len(tokens), vocabulary] of the tokens after those given before."""
        logits, self._self_k, self._self_v = self._decoder.run(
            ["logits", "new_self_k", "new_self_v"],
            {
                "tokens": np.array([list(tokens)], np.int64),
                "self_k": self._self_k,
                "self_v": self._self_v,
                "cross_k": self._cross_k,
                "cross_v": self._cross_v,
            },
            self._run,
        )
        return np.asarray(logits[0])
