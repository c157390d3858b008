"""fp32 against int8 (python -m bench.figures.int8 [--rounds N] [NAME ...]; section (e) of
python -m bench.figures.asr).

For each model directory bench/tools/family_models.py wrote (SPEECH_EVENT_FAMILY_MODELS=DIR: the
conformer-transducer large, the Parakeet-TDT 0.6B shape, Whisper base and small, random weights),
its int8 files are written once (speech_event/exporters/quantize.py, as export --int8 does). Then,
on 2 cores and on 1 (taskset -c 0), each figure in a process of its own so that its peak memory is
that engine's alone: our engine's real-time factor on 10 s of speech (the best of 3 runs after a
warm-up), its peak resident memory and the model's own share of it (what loading it added: the peak
also holds the interpreter's 70-odd MiB and a run's buffers), and the same directory through onnx-asr
(NeMo directories: onnx-asr reads ours as they are; Whisper in optimum's layout, which
bench/parity/whisper_optimum_parity.py writes, as its "whisper" model; it has no reader for export-whisper's
layout), its RTF and ours divided by it. The two run in turns, --rounds processes each (5
by default; a shared machine's load changes from minute to minute: in turns it weighs on both
alike), each figure the median of its rounds; the ratio's range is that of the rounds' own ratios.
Last, how often int8 says what fp32 says on the command utterances.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable, Dict, List, Optional

import numpy as np

from bench.figures.measures import peak_mib, resident_mib, robot_commands, word_errors
from fixtures.tts import speak_tts
from speech_event.config import SpeechEventConfig
from speech_event.exporters.quantize import quantize_directory
from speech_event.ports import Recognizer
from speech_event.recognizers import RECOGNIZERS
from speech_event.recognizers.nemo.manifest import CONFORMER_TRANSDUCER
from speech_event.recognizers.onnx.directory import MANIFEST_FILE, int8_file
from speech_event.recognizers.onnx.families import family_of
from speech_event.recognizers.whisper.manifest import WHISPER
from speech_event.recognizers.whisper.optimum_layout import is_optimum_directory

SECONDS = 10
RUNS = 3


def _speech() -> np.ndarray:
    return np.concatenate([speak_tts(command, 16000) for command in robot_commands()])[: SECONDS * 16000]


def _engine(directory: Path, quantization: str) -> Recognizer:
    config = SpeechEventConfig(
        model=family_of(directory, unrecorded=CONFORMER_TRANSDUCER),
        en_model_path=str(directory),
        quantization=quantization,
    )
    return RECOGNIZERS["auto"](config)


def _onnx_asr(directory: Path, quantization: str) -> Optional[Callable[[np.ndarray], object]]:
    """onnx-asr's model on ``directory``; None for a directory it has no reader for."""
    import onnx_asr

    if family_of(directory, unrecorded=CONFORMER_TRANSDUCER) == WHISPER:
        if not is_optimum_directory(directory):
            return None
        model_type, language = "whisper", {"language": "en"}
    else:
        model_type, language = json.loads((directory / MANIFEST_FILE).read_text())["model_type"], {}
    model = onnx_asr.load_model(
        model_type, directory, quantization=None if quantization == "none" else "int8"
    )
    return lambda audio: model.recognize(audio, sample_rate=16000, **language)


def _measure(load: Callable[[], Optional[Callable[[np.ndarray], object]]]) -> Optional[Dict[str, float]]:
    """``load``'s model: its RTF, the process's peak memory and what loading it added to the
    resident memory (the model's own share, without the interpreter's and the run's buffers)."""
    audio = _speech()
    before = resident_mib()
    transcribe = load()
    if transcribe is None:
        return None
    loaded = resident_mib() - before
    transcribe(audio)  # warm
    best = float("inf")
    for _ in range(RUNS):
        started = time.perf_counter()
        transcribe(audio)
        best = min(best, time.perf_counter() - started)
    return {"rtf": best / SECONDS, "peak_mib": peak_mib(), "loaded_mib": loaded}


def one(runtime: str, directory: Path, quantization: str) -> None:
    """In a process of its own: one engine's figures, as one JSON line."""
    if runtime == "ours":
        figures = _measure(lambda: _engine(directory, quantization).transcribe)
    else:
        figures = _measure(lambda: _onnx_asr(directory, quantization))
    print(json.dumps(figures))


def _run(runtime: str, directory: Path, quantization: str, cores: int) -> Optional[Dict[str, float]]:
    command = [sys.executable, "-m", "bench.figures.int8", "--one", runtime, str(directory), quantization]
    if cores == 1:
        command = ["taskset", "-c", "0", *command]
    output = subprocess.run(command, check=True, capture_output=True, text=True).stdout
    result: Optional[Dict[str, float]] = json.loads(output.strip().splitlines()[-1])
    return result


def _agreement(directory: Path) -> str:
    """How often int8 says what fp32 says, each command an utterance of its own."""
    fp32, int8 = _engine(directory, "none"), _engine(directory, "int8")
    commands = robot_commands()
    same = edits = words = 0
    for command in commands:
        audio = speak_tts(command, 16000)
        said, quantized = fp32.transcribe(audio).text, int8.transcribe(audio).text
        same += said == quantized
        errors, count = word_errors(said, quantized)
        edits, words = edits + errors, words + count
    agreement = 1 - edits / words if words else 1.0
    return f"int8 says what fp32 says on {same}/{len(commands)} utterances, word agreement {agreement:.3f}"


def _line(name: str, quantization: str, cores: int, directory: Path, rounds: int) -> str:
    ours: List[Dict[str, float]] = []
    theirs: List[Dict[str, float]] = []
    readable = True  # by onnx-asr
    for _ in range(rounds):
        mine = _run("ours", directory, quantization, cores)
        assert mine is not None
        ours.append(mine)
        other = _run("onnx-asr", directory, quantization, cores) if readable else None
        readable = other is not None
        if other is not None:
            theirs.append(other)
    figures = f"RTF {_median(ours, 'rtf'):.3f}, {_memory(ours)}"
    if not theirs:
        compared = "onnx-asr: no reader for this layout"
    else:
        ratios = [mine["rtf"] / other["rtf"] for mine, other in zip(ours, theirs)]
        compared = (
            f"onnx-asr RTF {_median(theirs, 'rtf'):.3f}, {_memory(theirs)}; "
            f"ours / onnx-asr {_median(ours, 'rtf') / _median(theirs, 'rtf'):.2f} "
            f"(rounds {min(ratios):.2f} to {max(ratios):.2f})"
        )
    return f"(e) {name:18s} {quantization:4s} {cores} core{'s' if cores > 1 else ' '}: {figures}; {compared}"


def _memory(rounds: List[Dict[str, float]]) -> str:
    return f"peak {_median(rounds, 'peak_mib'):.0f} MiB (model {_median(rounds, 'loaded_mib'):.0f})"


def _median(rounds: List[Dict[str, float]], figure: str) -> float:
    return statistics.median(round_[figure] for round_ in rounds)


def figures(names: List[str], rounds: int = 5) -> None:
    """Every model directory bench/tools/family_models.py wrote, or those ``names`` name."""
    where = os.environ.get("SPEECH_EVENT_FAMILY_MODELS")
    if not where:
        print("(e) set SPEECH_EVENT_FAMILY_MODELS to the directory bench/tools/family_models.py wrote")
        return
    directories: List[Path] = sorted(
        path for path in Path(where).iterdir() if path.is_dir() and (not names or path.name in names)
    )
    for directory in directories:
        if not any(int8_file(directory, path.name) for path in directory.glob("*.onnx")):
            quantize_directory(directory)
        for cores in (2, 1):
            for quantization in ("none", "int8"):
                print(_line(directory.name, quantization, cores, directory, rounds), flush=True)
        print(f"(e) {directory.name:18s} {_agreement(directory)}", flush=True)


if __name__ == "__main__":
    if sys.argv[1:2] == ["--one"]:
        one(sys.argv[2], Path(sys.argv[3]), sys.argv[4])
        sys.exit(0)
    parser = argparse.ArgumentParser(description="fp32 against int8, ours beside onnx-asr (issue 21).")
    parser.add_argument("--rounds", type=int, default=5, help="processes of each, in turns")
    parser.add_argument("names", nargs="*", help="only these of bench/tools/family_models.py's directories")
    arguments = parser.parse_args()
    figures(arguments.names, arguments.rounds)
