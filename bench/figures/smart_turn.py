"""Smart Turn v3.2's cost a call (python -m bench.figures.smart_turn): the project's features and the
model on onnxruntime as the node runs it (smart_turn.THREADS) and on two threads, beside pipecat's
own features (``_whisper_features.py`` from the installed wheel) on the same audio, interleaved
call by call. The turn so far is each LJ Speech reading of
tests/recordings; milliseconds, median and 90th percentile over ``--rounds``.

With ``--after-engine``, what the node's decision waits for: Whisper tiny.en int8's text of each of
the robot's first 12 commands (festival's slt) and then the call, on each thread count, and the
call alongside the text as the node asks it (HeardAlongside), interleaved with the text alone (the
trained weights of the test extra). Printed; nothing is asserted.

    python -m bench.figures.smart_turn [--rounds 5] [--after-engine]
"""

import argparse
import time
from typing import Callable, Dict, List

import numpy as np

from bench.figures.grammar import ENGINES
from bench.figures.measures import robot_commands
from fixtures.festival import speak_festival
from fixtures.noises import read_audio
from fixtures.pipecat_smart_turn import as_pipecat_pads, pipecats_features
from fixtures.recordings import ljspeech
from harness.catalog import ScenarioEngines
from speech_event.config import SpeechEventConfig
from speech_event.recognizers.whisper.features import SAMPLE_RATE
from speech_event.turns.smart_turn import THREADS, HeardAlongside, SmartTurn, smart_turn_features

ENGINE = "tiny.en int8"


def since(began: float) -> float:
    """Milliseconds since ``began`` (time.perf_counter)."""
    return 1000 * (time.perf_counter() - began)


def milliseconds(call: Callable[..., object], *arguments: object) -> float:
    began = time.perf_counter()
    call(*arguments)
    return since(began)


def on(threads: int) -> str:
    return "1 thread" if threads == 1 else f"{threads} threads"


def report(title: str, times: Dict[str, List[float]]) -> None:
    print(title)
    for name, each in times.items():
        median, p90 = np.percentile(each, [50, 90])
        print(f"  {name:<32} median {median:6.1f} ms   90th percentile {p90:6.1f} ms")


def calls(models: Dict[int, SmartTurn], rounds: int) -> None:
    """The call alone on the readings, each thread count, and the features both ways."""
    reference = pipecats_features()
    turns = [read_audio(recording.path, SAMPLE_RATE) for recording in ljspeech()]
    times: Dict[str, List[float]] = {"features (ours)": [], "features (pipecat)": []}
    times.update({f"whole call, {on(threads)}": [] for threads in models})
    for _ in range(rounds):
        for audio in turns:
            times["features (ours)"].append(milliseconds(smart_turn_features, audio))
            padded = as_pipecat_pads(audio)
            times["features (pipecat)"].append(
                milliseconds(reference.compute_whisper_log_mel_features, padded)
            )
            for threads, model in models.items():
                times[f"whole call, {on(threads)}"].append(milliseconds(model.completion, audio))
    report(f"Smart Turn v3.2, {len(turns)} turns x {rounds} rounds", times)


def after_engine(models: Dict[int, SmartTurn], rounds: int) -> None:
    """The engine's text, then the call on the same audio (the gate's pause after it); and the
    call alongside the text (HeardAlongside, as the node asks it): when the text is there, and
    when both are. Each on each thread count."""
    recognizer, quantization = ENGINES[ENGINE]
    commands = [speak_festival(phrase, "slt", SAMPLE_RATE) for phrase in robot_commands()[:12]]
    alongside = {threads: HeardAlongside(model.complete) for threads, model in models.items()}
    try:
        with ScenarioEngines(recognizer, SpeechEventConfig(quantization=quantization)) as engines:
            engine = engines.build()
            for audio in commands:  # loaded and warm before anything is timed
                engine.transcribe(audio)
            times: Dict[str, List[float]] = {"the text alone": []}
            for _ in range(rounds):
                for audio in commands:
                    times["the text alone"].append(milliseconds(engine.transcribe, audio))
                    for threads, model in models.items():
                        began = time.perf_counter()
                        engine.transcribe(audio)
                        model.complete(audio, paused=True)
                        times.setdefault(f"the text, then {on(threads)}", []).append(since(began))
                        began = time.perf_counter()
                        verdict = alongside[threads].ask(audio, True)
                        engine.transcribe(audio)
                        times.setdefault(f"alongside, {on(threads)}: the text", []).append(since(began))
                        verdict.result()
                        times.setdefault(f"alongside, {on(threads)}: both", []).append(since(began))
    finally:
        for each in alongside.values():
            each.close()
    report(f"{ENGINE}'s text and Smart Turn v3.2, {len(commands)} commands x {rounds} rounds", times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--after-engine", action="store_true", help="the engine's text, then the call")
    arguments = parser.parse_args()
    models = {threads: SmartTurn(threads=threads) for threads in sorted({THREADS, 1, 2})}
    if arguments.after_engine:
        after_engine(models, arguments.rounds)
    else:
        calls(models, arguments.rounds)


if __name__ == "__main__":
    main()
