"""Silero VAD on onnxruntime: the highest speech probability in an utterance.

The model is the ONNX file that the ``silero-vad`` wheel ships (``silero_vad/data/silero_vad.onnx``);
install the wheel with ``pip install --no-deps silero-vad``, since its Python code imports torch,
which the robot does not need: this module finds the file without importing the package. The
model is stateful: 512-sample windows at 16 kHz, each with the 64 samples before it as context,
and the recurrent state carried from one window to the next.
"""

import importlib.util
from pathlib import Path
from typing import Callable, List, Tuple

import numpy as np

from speech_event.errors import ModelError
from speech_event.pipeline.resample import resample

SAMPLE_RATE = 16000
WINDOW = 512
CONTEXT = 64
_STATE_SHAPE = (2, 1, 128)


def silero_model_path() -> Path:
    """The ONNX file of the installed silero-vad wheel, or ModelError saying how to install it."""
    spec = importlib.util.find_spec("silero_vad")
    origin = spec.origin if spec is not None else None
    path = Path(origin).parent / "data" / "silero_vad.onnx" if origin else None
    if path is None or not path.is_file():
        raise ModelError(
            "vad_threshold needs Silero VAD's ONNX model, shipped in the silero-vad wheel: "
            "pip install --no-deps silero-vad (its torch dependency is not needed)"
        )
    return path


class SileroVad:
    """Silero VAD's ONNX model on onnxruntime (CPU, one thread): speech probabilities of 16 kHz audio."""

    def __init__(self, path: Path) -> None:
        import onnxruntime

        options = onnxruntime.SessionOptions()
        options.log_severity_level = 3
        # One thread: the VAD runs beside recognition, and a window is far too small to share out.
        options.intra_op_num_threads = 1
        options.inter_op_num_threads = 1
        try:
            self._session = onnxruntime.InferenceSession(
                str(path), options, providers=["CPUExecutionProvider"]
            )
        except Exception as problem:  # onnxruntime raises its own exception types
            raise ModelError(f"{path}: onnxruntime cannot load Silero VAD: {problem}") from None

    @staticmethod
    def initial_state() -> np.ndarray:
        return np.zeros(_STATE_SHAPE, dtype=np.float32)

    def window_probability(
        self, context: np.ndarray, window: np.ndarray, state: np.ndarray
    ) -> Tuple[float, np.ndarray]:
        """One 512-sample window with the 64 samples before it: its speech probability, the next state."""
        framed = np.concatenate([context, window])[None, :]
        rate = np.array(SAMPLE_RATE, dtype=np.int64)
        probability, state = self._session.run(None, {"input": framed, "state": state, "sr": rate})
        return float(probability[0, 0]), state

    def speech_probabilities(self, audio: np.ndarray) -> np.ndarray:
        """The speech probability of each 512-sample window of 16 kHz ``audio``."""
        state = self.initial_state()
        context = np.zeros(CONTEXT, dtype=np.float32)
        samples = np.asarray(audio, dtype=np.float32)
        probabilities: List[float] = []
        for start in range(0, samples.size - WINDOW + 1, WINDOW):
            window = samples[start : start + WINDOW]
            probability, state = self.window_probability(context, window, state)
            probabilities.append(probability)
            context = window[-CONTEXT:]
        return np.array(probabilities)

    def max_speech_probability(self, audio: np.ndarray) -> float:
        """The highest speech probability over the windows of 16 kHz ``audio`` (0 if shorter than one)."""
        probabilities = self.speech_probabilities(audio)
        return float(probabilities.max()) if probabilities.size else 0.0

    def non_speech(self, threshold: float) -> "Callable[[np.ndarray, int, int, int], np.ndarray]":
        """For the length cut: audio at its rate, the first sample of the search and the hop there
        -> for each hop from that sample on, True where the speech probability is below ``threshold``."""

        def non_speech(audio: np.ndarray, rate: int, first: int, hop: int) -> np.ndarray:
            region = resample(audio[first:], rate, SAMPLE_RATE)
            probabilities = self.speech_probabilities(region)
            hops = (audio.size - first) // hop
            frames = np.minimum(
                (np.arange(hops) * hop * SAMPLE_RATE / rate) // WINDOW, probabilities.size - 1
            )
            if probabilities.size == 0:
                return np.zeros(hops, dtype=bool)
            return np.asarray(probabilities[frames.astype(int)] < threshold)

        return non_speech
