"""The two ONNX files of speech-event export-whisper, run with onnxruntime.

``encoder.onnx``: ``mel`` float32 [1, n_mels, 3000] -> for each decoder block i its cross-attention
keys and values, computed once, split by head: ``cross_k_i`` [1, heads, head width, audio
positions] (scaled and transposed, ready to multiply) and ``cross_v_i`` [1, heads, audio
positions, head width]. One tensor a block: a decoding step slices nothing the size of the audio.
``decoder.onnx``: ``tokens`` int64 [1, n], ``self_k``, ``self_v`` [layers, 1, heads, past, head
width] (the self-attention cache of the tokens before), every ``cross_k_i``, ``cross_v_i`` ->
``logits`` [1, n, vocabulary], ``new_self_k``, ``new_self_v`` [layers, 1, heads, past + n, head
width]: a step costs one position.
Each may have an int8 version (``encoder.int8.onnx``), which the ``quantization`` key picks.

``WhisperOnnx`` and ``Decoding`` are what decoding needs of a model, whatever its layout: this one's,
or Hugging Face optimum's (optimum_model.py).
"""

import copy
from pathlib import Path
from typing import Dict, List, Optional, Protocol, Sequence

import numpy as np
import onnxruntime

from speech_event.errors import ModelError
from speech_event.recognizers.onnx.directory import CPU_FP32, Runtime
from speech_event.recognizers.onnx.session import check_tensors, last_dimension, open_session, providers

ENCODER_FILE = "encoder.onnx"
DECODER_FILE = "decoder.onnx"
ENCODER_INPUTS = {"mel": 3}
DECODER_INPUTS = {"tokens": 2, "self_k": 5, "self_v": 5}
DECODER_OUTPUTS = {"logits": 3, "new_self_k": 5, "new_self_v": 5}
WHISPER_DIRECTORY = (
    f"a Whisper model directory holds {ENCODER_FILE}, {DECODER_FILE}, tokens.txt and config.json "
    "(speech-event export-whisper CHECKPOINT DIR writes one)"
)
EXPORTER = "speech-event export-whisper"


class Decoding(Protocol):
    """One piece of audio's decoder: new tokens -> their logits [len(tokens), vocabulary]; it keeps
    the tokens before (its key/value cache), so each step costs what its new tokens cost."""

    def __call__(self, tokens: Sequence[int]) -> np.ndarray: ...

    def fork(self) -> "Decoding":
        """A decoding that goes on from the tokens given so far, apart from this one."""
        ...


class WhisperOnnx(Protocol):
    """A Whisper model's ONNX files, loaded: the audio's encoding and its decoding."""

    @property
    def vocabulary_size(self) -> Optional[int]:
        """The logits a step gives, when the file fixes it."""
        ...

    def decoding(self, mel: np.ndarray, run: Optional[onnxruntime.RunOptions] = None) -> Decoding:
        """The decoding of the audio whose log-mel window [mel bands, 3000] is ``mel``, no token given yet."""
        ...


def cross_names(layers: int) -> List[str]:
    """The encoder's outputs and the decoder's inputs: cross_k_i, cross_v_i for each of ``layers`` blocks."""
    return [f"cross_{kind}_{index}" for index in range(layers) for kind in ("k", "v")]


class WhisperModel:
    """encoder.onnx and decoder.onnx of an exported Whisper model, their tensors checked at load."""

    def __init__(self, directory: Path, runtime: Runtime = CPU_FP32) -> None:
        execution_providers = providers(runtime.cuda)
        encoder_path, decoder_path = (
            runtime.model_file(directory, ENCODER_FILE),
            runtime.model_file(directory, DECODER_FILE),
        )
        self._encoder = open_session(encoder_path, execution_providers, WHISPER_DIRECTORY)
        self.decoder = open_session(decoder_path, execution_providers, WHISPER_DIRECTORY)
        layers = sum(1 for arg in self._encoder.get_outputs() if arg.name.startswith("cross_k_"))
        if layers == 0:
            raise ModelError(
                f"{encoder_path}: no cross_k_0 output; {ENCODER_FILE} of {EXPORTER} gives each decoder "
                "block's cross-attention keys and values (cross_k_0, cross_v_0, ...)"
            )
        cross = {name: 4 for name in cross_names(layers)}
        check_tensors(encoder_path, "inputs", self._encoder.get_inputs(), ENCODER_INPUTS, EXPORTER)
        check_tensors(encoder_path, "outputs", self._encoder.get_outputs(), cross, EXPORTER)
        check_tensors(
            decoder_path, "inputs", self.decoder.get_inputs(), {**DECODER_INPUTS, **cross}, EXPORTER
        )
        check_tensors(decoder_path, "outputs", self.decoder.get_outputs(), DECODER_OUTPUTS, EXPORTER)
        self._cross_names = list(cross)

    @property
    def vocabulary_size(self) -> Optional[int]:
        return last_dimension(self.decoder, "logits")

    def encode(self, mel: np.ndarray, run: Optional[onnxruntime.RunOptions] = None) -> Dict[str, np.ndarray]:
        """Each block's cross-attention keys and values, by the decoder's input names."""
        outputs = self._encoder.run(self._cross_names, {"mel": mel[None].astype(np.float32)}, run)
        return dict(zip(self._cross_names, (np.asarray(output) for output in outputs)))

    def decoding(self, mel: np.ndarray, run: Optional[onnxruntime.RunOptions] = None) -> "DecoderSession":
        return DecoderSession(self, self.encode(mel, run), run)


class DecoderSession:
    """One utterance's decoding: the cross-attention of its audio and the growing self-attention cache."""

    def __init__(
        self,
        model: WhisperModel,
        cross: Dict[str, np.ndarray],
        run: Optional[onnxruntime.RunOptions] = None,
    ) -> None:
        self._decoder = model.decoder
        self._cross = cross
        _, heads, _, head_width = cross["cross_v_0"].shape
        layers = len(cross) // 2
        self._self_k = self._self_v = np.zeros((layers, 1, heads, 0, head_width), np.float32)
        self._run = run

    def __call__(self, tokens: Sequence[int]) -> np.ndarray:
        """The logits [len(tokens), vocabulary] of the tokens after those given before."""
        inputs = {
            "tokens": np.array([list(tokens)], np.int64),
            "self_k": self._self_k,
            "self_v": self._self_v,
        }
        logits, self._self_k, self._self_v = self._decoder.run(
            ["logits", "new_self_k", "new_self_v"], {**inputs, **self._cross}, self._run
        )
        return np.asarray(logits[0])

    def fork(self) -> "DecoderSession":
        """A session that goes on from the tokens given so far, apart from this one: many phrases are
        scored after one prompt, whose decoder pass they share. A call replaces the cache's arrays,
        never writes into them, so the two share them until each runs on."""
        return copy.copy(self)
