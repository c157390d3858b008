"""The ONNX files of NeMo's exports, run with onnxruntime.

A transducer (RNN-T or TDT) is two files:
``encoder-model.onnx``: ``audio_signal`` float32 [B, features, T] and ``length`` int64 [B] ->
``outputs`` [B, D, T'] and ``encoded_lengths`` [B].
``decoder_joint-model.onnx``: ``encoder_outputs`` [B, D, 1], ``targets`` int32 [B, 1],
``target_length`` int32 [B], ``input_states_1`` and ``input_states_2`` (LSTM h and c, [layers, B,
hidden]) -> ``outputs`` (logits, last dimension V + 1, then TDT's durations), ``prednet_lengths``,
``output_states_1``, ``output_states_2``.
A CTC model (or a hybrid model's CTC head) is one file, ``model.onnx``: ``audio_signal`` and
``length`` as above -> ``logprobs`` [B, T', V + 1].
"""

from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np
import onnxruntime

from speech_event.recognizers.onnx.session import check_tensors, last_dimension, open_session, providers

ENCODER_FILE = "encoder-model.onnx"
DECODER_JOINT_FILE = "decoder_joint-model.onnx"
CTC_FILE = "model.onnx"
CTC_OUTPUTS = {"logprobs": 3}
ENCODER_INPUTS = {"audio_signal": 3, "length": 1}
ENCODER_OUTPUTS = {"outputs": 3, "encoded_lengths": 1}
DECODER_INPUTS = {
    "encoder_outputs": 3,
    "targets": 2,
    "target_length": 1,
    "input_states_1": 3,
    "input_states_2": 3,
}
DECODER_OUTPUTS = {"outputs": -1, "prednet_lengths": -1, "output_states_1": 3, "output_states_2": 3}

LstmState = Tuple[np.ndarray, np.ndarray]


NEMO_DIRECTORY = (
    f"a model directory holds {ENCODER_FILE}, {DECODER_JOINT_FILE} (a transducer) or {CTC_FILE} (CTC), "
    "vocab.txt and config.json (speech-event export-nemo MODEL.nemo DIR writes one)"
)


def _session(path: Path, execution_providers: List[str]) -> onnxruntime.InferenceSession:
    return open_session(path, execution_providers, NEMO_DIRECTORY)


def _check(path: Path, kind: str, found: Sequence[onnxruntime.NodeArg], expected: Dict[str, int]) -> None:
    check_tensors(path, kind, found, expected, "a NeMo export")


def _audio_inputs(features: np.ndarray) -> Dict[str, np.ndarray]:
    """The encoder's (or CTC model's) inputs for one utterance's features [features, T]."""
    return {
        "audio_signal": features[None].astype(np.float32),
        "length": np.array([features.shape[1]], np.int64),
    }


class TransducerModel:
    """A transducer's two ONNX files (RNN-T or TDT): the encoder, and the decoder-joint, run a step a time."""

    def __init__(self, directory: Path, cuda: bool) -> None:
        encoder_path, decoder_path = directory / ENCODER_FILE, directory / DECODER_JOINT_FILE
        execution_providers = providers(cuda)  # decided once, so a missing CUDA is said once
        self._encoder = _session(encoder_path, execution_providers)
        self._decoder_joint = _session(decoder_path, execution_providers)
        _check(encoder_path, "inputs", self._encoder.get_inputs(), ENCODER_INPUTS)
        _check(encoder_path, "outputs", self._encoder.get_outputs(), ENCODER_OUTPUTS)
        _check(decoder_path, "inputs", self._decoder_joint.get_inputs(), DECODER_INPUTS)
        _check(decoder_path, "outputs", self._decoder_joint.get_outputs(), DECODER_OUTPUTS)
        states = {arg.name: arg.shape for arg in self._decoder_joint.get_inputs()}
        self._state_shapes = [states["input_states_1"], states["input_states_2"]]

    @property
    def logits_size(self) -> Optional[int]:
        """The decoder-joint's logits per step when the file says (V + 1, plus TDT's durations)."""
        return last_dimension(self._decoder_joint, "outputs")

    def encode(self, features: np.ndarray, run: Optional[onnxruntime.RunOptions] = None) -> np.ndarray:
        """[features, T] -> encoder frames [T', D]. ``run.terminate`` stops it (it raises)."""
        outputs, lengths = self._encoder.run(
            ["outputs", "encoded_lengths"],
            _audio_inputs(features),
            run,
        )
        return np.asarray(outputs[0, :, : int(lengths[0])].T)

    def initial_state(self) -> LstmState:
        h, c = (np.zeros((int(shape[0]), 1, int(shape[2])), dtype=np.float32) for shape in self._state_shapes)
        return h, c

    def step(
        self,
        frame: np.ndarray,
        last_token: int,
        state: LstmState,
        run: Optional[onnxruntime.RunOptions] = None,
    ) -> Tuple[np.ndarray, LstmState]:
        logits, h, c = self._decoder_joint.run(
            ["outputs", "output_states_1", "output_states_2"],
            {
                "encoder_outputs": frame[None, :, None].astype(np.float32),
                "targets": np.array([[last_token]], dtype=np.int32),
                "target_length": np.array([1], dtype=np.int32),
                "input_states_1": state[0],
                "input_states_2": state[1],
            },
            run,
        )
        return np.asarray(logits).reshape(-1), (h, c)


class CtcModel:
    """A CTC model's one ONNX file: features in, per-frame log-probabilities out."""

    def __init__(self, directory: Path, cuda: bool) -> None:
        path = directory / CTC_FILE
        self._model = _session(path, providers(cuda))
        _check(path, "inputs", self._model.get_inputs(), ENCODER_INPUTS)
        _check(path, "outputs", self._model.get_outputs(), CTC_OUTPUTS)

    @property
    def logits_size(self) -> Optional[int]:
        return last_dimension(self._model, "logprobs")

    def logits(self, features: np.ndarray, run: Optional[onnxruntime.RunOptions] = None) -> np.ndarray:
        """[features, T] -> per-frame log-probabilities [T', V + 1]."""
        (logprobs,) = self._model.run(
            ["logprobs"],
            _audio_inputs(features),
            run,
        )
        return np.asarray(logprobs[0])
