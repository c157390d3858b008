"""The ONNX files of NeMo's exports (onnx_files.py: their names and tensors), run with onnxruntime."""

from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np
import onnxruntime

from speech_event.recognizers.nemo.onnx_files import (
    CTC_FILE,
    CTC_OUTPUTS,
    DECODER_INPUTS,
    DECODER_JOINT_FILE,
    DECODER_OUTPUTS,
    ENCODER_FILE,
    ENCODER_INPUTS,
    ENCODER_OUTPUTS,
    NEMO_DIRECTORY,
)
from speech_event.recognizers.onnx.directory import CPU_FP32, Runtime
from speech_event.recognizers.onnx.session import check_tensors, last_dimension, open_session, providers

LstmState = Tuple[np.ndarray, np.ndarray]


def _session(path: Path, execution_providers: List[str]) -> onnxruntime.InferenceSession:
    return open_session(path, execution_providers, NEMO_DIRECTORY)


def _check(path: Path, kind: str, found: Sequence[onnxruntime.NodeArg], expected: Dict[str, int]) -> None:
    check_tensors(path, kind, found, expected, "a NeMo export")


_ONE = np.ones(1, dtype=np.int32)  # a target_length of one token


def _audio_inputs(features: np.ndarray) -> Dict[str, np.ndarray]:
    """The encoder's (or CTC model's) inputs for one utterance's features [features, T]."""
    return {
        "audio_signal": features[None].astype(np.float32),
        "length": np.array([features.shape[1]], np.int64),
    }


class TransducerModel:
    """A transducer's two ONNX files (RNN-T or TDT): the encoder, and the decoder-joint, run a step a time."""

    def __init__(self, directory: Path, runtime: Runtime = CPU_FP32) -> None:
        encoder_path, decoder_path = (
            runtime.model_file(directory, ENCODER_FILE),
            runtime.model_file(directory, DECODER_JOINT_FILE),
        )
        execution_providers = providers(runtime.cuda)  # decided once, so a missing CUDA is said once
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
        # Contiguous, so that each frame goes to the decoder-joint without a copy of its own.
        return np.ascontiguousarray(outputs[0, :, : int(lengths[0])].T)

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
        """The logits at ``frame`` [D] after ``last_token``, and the state after consuming it.

        Greedy decoding's hot loop (a call per frame and per token): the inputs are built directly,
        without ``joint``'s batching copies."""
        logits, h, c = self._decoder_joint.run(
            ["outputs", "output_states_1", "output_states_2"],
            {
                "encoder_outputs": frame.reshape(1, -1, 1),
                "targets": np.array([[last_token]], dtype=np.int32),
                "target_length": _ONE,
                "input_states_1": state[0],
                "input_states_2": state[1],
            },
            run,
        )
        return np.asarray(logits).reshape(-1), (h, c)

    def joint(
        self,
        frames: np.ndarray,
        last_tokens: Sequence[int],
        states: LstmState,
        run: Optional[onnxruntime.RunOptions] = None,
    ) -> Tuple[np.ndarray, LstmState]:
        """Each of ``last_tokens`` (N, its state the N-th of ``states``, [layers, N, hidden]) against
        every one of ``frames`` [T', D], in one decoder-joint call of batch N * T' (NeMo exports the
        batch axis dynamic): logits [N, T', logits] and the states after each token [layers, N, hidden].
        The prediction network never sees the frames, so a token's state after is the same for every
        frame: the first frame's is kept.
        """
        count, length = len(last_tokens), len(frames)
        logits, h, c = self._decoder_joint.run(
            ["outputs", "output_states_1", "output_states_2"],
            {
                "encoder_outputs": np.tile(frames[:, :, None], (count, 1, 1)).astype(np.float32),
                "targets": np.repeat(np.asarray(last_tokens, dtype=np.int32), length)[:, None],
                "target_length": np.ones(count * length, dtype=np.int32),
                "input_states_1": np.repeat(states[0], length, axis=1),
                "input_states_2": np.repeat(states[1], length, axis=1),
            },
            run,
        )
        return np.asarray(logits).reshape(count, length, -1), (h[:, ::length], c[:, ::length])

    def lattice(
        self,
        frames: np.ndarray,
        tokens: Sequence[int],
        blank: int,
        run: Optional[onnxruntime.RunOptions] = None,
    ) -> np.ndarray:
        """The joint's logits [T', U + 1, logits] at every frame after the start (the blank, as
        greedy decoding starts) and each prefix of ``tokens``: U + 1 decoder-joint calls, each over all
        frames. Call u feeds ``tokens[u - 1]`` with the state after call u - 1, as greedy decoding
        moves the state on only with a token."""
        state, columns = self.initial_state(), []
        for last in [blank, *tokens]:
            logits, state = self.joint(frames, [last], state, run)
            columns.append(logits[0])
        return np.stack(columns, axis=1)


class CtcModel:
    """A CTC model's one ONNX file: features in, per-frame log-probabilities out."""

    def __init__(self, directory: Path, runtime: Runtime = CPU_FP32) -> None:
        path = runtime.model_file(directory, CTC_FILE)
        self._model = _session(path, providers(runtime.cuda))
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
