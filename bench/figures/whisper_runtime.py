"""One Whisper runtime measured in a process of its own, for bench/figures/whisper_peer.py, which starts it:
python -m bench.figures.whisper_runtime RUNTIME DIRECTORY PRECISION THREADS prints one JSON line (Figures).

- ``ours``: the project's Whisper engine as the node builds it (model whisper, quantization none or
  int8) on export-whisper's directory;
- ``faster-whisper``: its WhisperModel (compute_type float32 or int8) on the faster-whisper
  directory of the same weights, decoding as ours does: greedy (beam 1, temperature 0 alone, so no
  fallback), no timestamps, no VAD, each recording on its own (no previous text), English.

Its own process, so that its peak memory (VmHWM) is this runtime's alone. Both are held to THREADS
cores (the first of those this process may use) and THREADS compute threads, so that neither gets
more of the machine than the other: faster-whisper's cpu_threads, onnxruntime's intra-op threads.
"""

import json
import os
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable, List

import numpy as np

from bench.figures.measures import peak_mib, resident_mib
from fixtures.recordings import SAMPLE_RATE, Recording, cards, librivox

FP32, INT8 = "fp32", "int8"
PRECISIONS = (FP32, INT8)
OURS, FASTER_WHISPER = "ours", "faster-whisper"
RUNTIMES = (OURS, FASTER_WHISPER)
Transcribe = Callable[[np.ndarray], str]


@dataclass(frozen=True)
class Figures:
    """One process's measurement, the JSON line it prints."""

    decode_seconds: float  # every recording transcribed once, after one warm-up
    audio_seconds: float
    peak_mib: float  # the process's peak resident memory
    model_mib: float  # what loading the model added to the resident memory
    texts: List[str]  # one a recording, in recordings()'s order

    @property
    def rtf(self) -> float:
        return self.decode_seconds / self.audio_seconds


def recordings() -> List[Recording]:
    """pocketsphinx-testdata's ten: cards, then librivox."""
    return cards() + librivox()


def _our_threads(threads: int) -> None:
    """Every onnxruntime session opened from now on gets ``threads`` intra-op threads. The engine
    (speech_event/recognizers/onnx/session.py) takes onnxruntime's default, which counts the
    machine's cores whatever the affinity (two threads on one core of this 2-core machine), and
    the configuration has no key for it: the bench sets it on the options the engine makes."""
    import onnxruntime

    class Threaded(onnxruntime.SessionOptions):  # type: ignore[misc]
        def __init__(self) -> None:
            super().__init__()
            self.intra_op_num_threads = threads

    onnxruntime.SessionOptions = Threaded


def _ours(directory: Path, precision: str, threads: int) -> Transcribe:
    from speech_event.config import SpeechEventConfig
    from speech_event.recognizers import RECOGNIZERS
    from speech_event.recognizers.whisper.manifest import WHISPER

    _our_threads(threads)
    config = SpeechEventConfig(
        model=WHISPER, en_model_path=str(directory), quantization="int8" if precision == INT8 else "none"
    )
    engine = RECOGNIZERS["whisper"](config)
    return lambda audio: engine.transcribe(audio).text


def _faster_whisper(directory: Path, precision: str, threads: int) -> Transcribe:
    from faster_whisper import WhisperModel

    model = WhisperModel(
        str(directory),
        device="cpu",
        compute_type="int8" if precision == INT8 else "float32",
        cpu_threads=threads,
        num_workers=1,
    )

    def transcribe(audio: np.ndarray) -> str:
        segments, _ = model.transcribe(
            audio,
            language="en",
            beam_size=1,
            temperature=0.0,
            without_timestamps=True,
            vad_filter=False,
            condition_on_previous_text=False,
            # Ours publishes what it decodes; faster-whisper would drop a segment it judges
            # silence (no_speech_prob over 0.6 with a low log probability).
            no_speech_threshold=None,
        )
        return " ".join(segment.text.strip() for segment in segments)  # decoding runs here, lazily

    return transcribe


def _imported(runtime: str) -> None:
    """The runtime's packages, imported before the resident memory is read so that the model's share
    is its loading alone."""
    if runtime == OURS:
        import onnxruntime  # noqa: F401

        import speech_event.recognizers.whisper.recognizer  # noqa: F401
    else:
        import faster_whisper  # noqa: F401


def measure(runtime: str, directory: Path, precision: str, threads: int) -> Figures:
    os.sched_setaffinity(0, sorted(os.sched_getaffinity(0))[:threads])  # before any pool starts
    audio = [recording.samples() for recording in recordings()]
    _imported(runtime)
    before = resident_mib()
    transcribe = (_ours if runtime == OURS else _faster_whisper)(directory, precision, threads)
    loaded = resident_mib() - before
    transcribe(audio[0])  # warm: the first run's allocations and lazy set-up
    texts: List[str] = []
    busy = 0.0
    for samples in audio:
        started = time.perf_counter()
        texts.append(transcribe(samples))
        busy += time.perf_counter() - started
    seconds = sum(samples.size for samples in audio) / SAMPLE_RATE
    return Figures(busy, seconds, peak_mib(), loaded, texts)


if __name__ == "__main__":
    runtime, where, precision, threads = sys.argv[1:5]
    print(json.dumps(asdict(measure(runtime, Path(where), precision, int(threads)))))
