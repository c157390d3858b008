"""Smart Turn v3.2 on onnxruntime: whether a speaker's turn is complete, heard in the audio.

The model is the ONNX file the ``pipecat-ai`` wheel ships
(``pipecat/audio/turn/smart_turn/data/smart-turn-v3.2-cpu.onnx``, BSD 2-Clause, Daily); install the
wheel with ``pip install --no-deps pipecat-ai``: this module finds the file without importing the
package, whose Python code wants much that the robot does not. Its input is the last 8 s of the
turn at 16 kHz, zero-padded at the front, normalised to zero mean and unit variance, as Whisper's
80-band log-mel of that buffer (reflected at both ends; transformers' WhisperFeatureExtractor,
which pipecat's ``_whisper_features.py`` vendors); its output the probability that the turn is
complete, complete above 0.5 (as pipecat reads it).

The file is int8 in QDQ form; it runs as float (exporters/dequantize.py: its weights dequantized,
its activations not rounded), because onnxruntime's integer kernels differ by CPU and round the
activations: with them a reading's score moved by 0.11 when its samples moved by one part in a
million, and a reading's end scored 0.42 on one CPU and under 0.25 on another. As float the same
audio scores the same to a part in a million on every CPU (docs/decisions.md, 2026-12-07).
"""

import importlib.util
import logging
import threading
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Callable, Optional

import numpy as np

from speech_event.config import SpeechEventConfig
from speech_event.errors import ModelError
from speech_event.exporters.dequantize import float_graph
from speech_event.pipeline.resample import resample
from speech_event.ports import ClosesSentences, Recognizer
from speech_event.recognizers.whisper.features import SAMPLE_RATE, window_log_mel

_LOG = logging.getLogger(__name__)

MODEL_FILE = "smart-turn-v3.2-cpu.onnx"
# Where turn_end_model auto hears: Smart Turn's languages include English, not Kinyarwanda.
ENGLISH = "english"
WINDOW_SAMPLES = 8 * SAMPLE_RATE
MEL_BANDS = 80
COMPLETE = 0.5
# pipecat asks once its VAD has heard 0.2 s without speech, which the turn then ends with. The
# robot's gate sends no blocks in a pause: a turn that ends at its last block ends mid-sound to the
# model ("stop", "turn left": 0.07 to 0.09 as slt says them; with 0.2 s of silence 0.87 to 0.95).
# Such a turn is topped up with silence to end in that much quiet (30 dB under its loudest 20 ms):
# the node decides only once the pause has lasted that long. A turn cut in its samples ends in
# the pause as heard already; more silence would tip a reader's pause inside a word to
# "complete" (LJ001-0008's "surpassed").
HEARD_PAUSE = int(0.2 * SAMPLE_RATE)
QUIET_FRAME = SAMPLE_RATE // 50
QUIET = 1e-3
_VARIANCE_FLOOR = 1e-7  # transformers' zero-mean unit-variance normalisation


def smart_turn_model_path() -> Path:
    """The ONNX file of the installed pipecat-ai wheel, or ModelError saying how to install it."""
    spec = importlib.util.find_spec("pipecat")
    origin = spec.origin if spec is not None else None
    path = Path(origin).parent / "audio" / "turn" / "smart_turn" / "data" / MODEL_FILE if origin else None
    if path is None or not path.is_file():
        raise ModelError(
            f"turn_end_model smart-turn needs Smart Turn v3.2's ONNX model ({MODEL_FILE}), shipped in "
            "the pipecat-ai wheel: pip install --no-deps pipecat-ai (none of its dependencies is needed)"
        )
    return path


def smart_turn_features(audio: np.ndarray) -> np.ndarray:
    """[80, 800] features of the turn so far (16 kHz): its last 8 s, zeros before a shorter one."""
    samples = np.asarray(audio, dtype=np.float32)[-WINDOW_SAMPLES:]
    buffer = np.zeros(WINDOW_SAMPLES, dtype=np.float32)
    buffer[WINDOW_SAMPLES - samples.size :] = samples
    # in float32, as the reference normalises the padded buffer before the spectrum's float64
    buffer = (buffer - buffer.mean()) / np.sqrt(buffer.var() + np.float32(_VARIANCE_FLOOR))
    return window_log_mel(buffer, MEL_BANDS)


def float_smart_turn(path: Path) -> bytes:
    """The model at ``path`` as a float graph (the module's docstring), serialized for onnxruntime;
    ModelError when onnx, which reads it, is not installed, or the file is not such a model."""
    try:
        import onnx
    except ImportError:
        raise ModelError(
            "turn_end_model smart-turn needs onnx to run Smart Turn's int8 file as float: pip install onnx"
        ) from None
    try:
        serialized: bytes = float_graph(onnx.load(str(path))).SerializeToString()
    except Exception as problem:  # protobuf's DecodeError, OSError, float_graph's ValueError
        raise ModelError(f"{path}: not Smart Turn's QDQ ONNX model: {problem}") from None
    return serialized


# Threads a call: one, as pipecat runs it, beside the engine's own (HeardAlongside). Two took 86
# ms a call instead of 100 alone, but beside the engine they only took its cores: Whisper tiny.en
# int8's text and the verdict alongside came 456 ms after the start on two against 379 on one
# (median, the robot's 12 commands x 4 rounds, interleaved, the AVX2 EPYC's 2 cores:
# bench/figures/smart_turn.py --after-engine).
THREADS = 1


THREAD_NAME = "speech_event_turn_end"  # HeardAlongside's


class SmartTurn:
    """Smart Turn's ONNX model on onnxruntime (CPU): the probability that the turn in 16 kHz audio
    is complete."""

    def __init__(self, path: Optional[Path] = None, threads: int = THREADS) -> None:
        import onnxruntime

        path = smart_turn_model_path() if path is None else path
        graph = float_smart_turn(path)
        options = onnxruntime.SessionOptions()
        options.log_severity_level = 3
        options.intra_op_num_threads = threads
        options.inter_op_num_threads = 1
        options.execution_mode = onnxruntime.ExecutionMode.ORT_SEQUENTIAL
        try:
            self._session = onnxruntime.InferenceSession(graph, options, providers=["CPUExecutionProvider"])
        except Exception as problem:  # onnxruntime raises its own exception types
            raise ModelError(f"{path}: onnxruntime cannot load Smart Turn: {problem}") from None

    def completion(self, audio: np.ndarray) -> float:
        """The probability that the turn so far (16 kHz ``audio``) is complete."""
        features = smart_turn_features(audio)[None]
        (probability,) = self._session.run(None, {"input_features": features})
        return float(np.asarray(probability).reshape(-1)[0])

    def complete(self, audio: np.ndarray, paused: bool = False) -> bool:
        """Whether the turn so far is complete: completion() above 0.5; ``paused``: the pause came as
        no blocks after ``audio`` (the robot's gate), which then ends in it (with_pause)."""
        return self.completion(with_pause(audio) if paused else audio) > COMPLETE


def with_pause(audio: np.ndarray) -> np.ndarray:
    """16 kHz ``audio`` followed by silence, so that it ends in HEARD_PAUSE of quiet."""
    samples = np.asarray(audio, dtype=np.float32)
    whole = samples[samples.size % QUIET_FRAME :].astype(np.float64)
    energies = np.mean(np.square(whole).reshape(-1, QUIET_FRAME), axis=1) if whole.size else np.zeros(0)
    loud = np.flatnonzero(energies >= energies.max() * QUIET) if energies.size else np.zeros(0, int)
    quiet = (energies.size - 1 - int(loud[-1])) * QUIET_FRAME if loud.size else samples.size
    return np.concatenate([samples, np.zeros(max(0, HEARD_PAUSE - quiet), np.float32)])


# The turn so far at the configuration's sample rate, and whether its pause came as no blocks ->
# whether the turn is complete.
TurnHeard = Callable[[np.ndarray, bool], bool]


def smart_turn_installed() -> bool:
    """Whether Smart Turn's model and onnx, which runs it, are installed (turn_end_model auto)."""
    try:
        smart_turn_model_path()
    except ModelError:
        return False
    return importlib.util.find_spec("onnx") is not None


class TurnEnd:
    """The configuration's turn-end model (turn_end_model) and where it hears: smart-turn in free
    speech with every engine that can be stopped; auto where its figures were measured, in English
    with an engine that closes sentences (ClosesSentences: Whisper), when the model is installed.
    The model is loaded where it will hear (``prepare``: as the node starts and at set_language),
    never on the worker, whose first decision would wait for it; a node that never hears with it
    never loads it."""

    def __init__(self, config: SpeechEventConfig, model: Optional[Callable[[], SmartTurn]] = None) -> None:
        """``model``: how the model is made (SmartTurn; a test's own)."""
        self._everywhere = config.turn_end_model == "smart-turn"
        self._rate = config.sample_rate
        self._make = SmartTurn if model is None else model
        self._model: Optional[SmartTurn] = None
        self._loading = threading.Lock()

    def hears(self, language: str, recognizer: Recognizer) -> bool:
        """Whether the model hears turns with ``recognizer`` transcribing ``language``."""
        return self._everywhere or (language == ENGLISH and isinstance(recognizer, ClosesSentences))

    def prepare(self, language: str, recognizer: Recognizer) -> None:
        """Load the model if it hears with ``recognizer`` and ``language``; ModelError if it cannot."""
        if self.hears(language, recognizer):
            self._loaded()

    def heard(self, audio: np.ndarray, paused: bool) -> bool:
        """TurnHeard: whether the turn so far (at the configuration's rate) is complete."""
        return self._loaded().complete(resample(audio, self._rate, SAMPLE_RATE), paused)

    def _loaded(self) -> SmartTurn:
        with self._loading:
            if self._model is None:
                self._model = self._make()
            return self._model


def turn_end_for(config: SpeechEventConfig) -> Optional[TurnEnd]:
    """The configuration's turn-end model; None for none, and for auto where Smart Turn is not
    installed (the turn then ends at the pause, as with none). smart-turn not installed: the
    ModelError of smart_turn_model_path, as the node starts."""
    if config.turn_end_model == "none":
        return None
    if config.turn_end_model == "auto" and not smart_turn_installed():
        _LOG.info(
            "turn_end_model auto: Smart Turn is not installed (pip install --no-deps pipecat-ai==1.14.0), "
            "so in free speech a turn ends at the pause"
        )
        return None
    if config.turn_end_model == "smart-turn":
        smart_turn_model_path()
    return TurnEnd(config)


class HeardAlongside:
    """What the turn-end model hears (TurnHeard), asked on a thread of its own: the background runs
    ask it as a speculation's engine starts on the same audio, and wait for the verdict only where
    the text needs it (a complete text that is not one of complete_answers; elsewhere they drop it,
    unheard if it has not started), so that the two share the cores instead of taking turns.
    Measured (bench/figures/smart_turn.py --after-engine, the robot's 12 commands, Whisper tiny.en
    int8, the AVX2 EPYC's 2 cores, medians): the text and the verdict 379 ms, against 483 one after
    the other; a text that needs no verdict ("yes") 379 against 326 alone.

    A thread of its own even on the fake clock: the worker's job waits for the verdict, which a
    simulated executor would not run meanwhile; the verdict is a function of the audio, so when
    it runs decides nothing. Once closed (the node stopped) it hears nothing more: the verdict is
    "not complete" at once, so that no turn ends early after the node stopped."""

    def __init__(self, heard: TurnHeard) -> None:
        self._heard = heard
        self._thread = ThreadPoolExecutor(max_workers=1, thread_name_prefix=THREAD_NAME)

    def ask(self, audio: np.ndarray, paused: bool) -> "Future[bool]":
        """The verdict on the turn so far, on its way."""
        try:
            return self._thread.submit(self._heard, audio, paused)
        except RuntimeError:  # closed: no thread takes it any more
            verdict: Future[bool] = Future()  # novermin: annotations in a function are not evaluated
            verdict.set_result(False)
            return verdict

    def close(self) -> None:
        """No more verdicts; those asked already are heard (or dropped) on the thread, which then ends."""
        self._thread.shutdown(wait=False)
