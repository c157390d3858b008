"""Smart Turn v3.2's cost a call (python -m bench.figures.smart_turn): the project's features and the
model on onnxruntime (one thread, as the node runs it), beside pipecat's own features
(``_whisper_features.py`` from the installed wheel) on the same audio, interleaved call by call.
The turn so far is each LJ Speech reading of tests/recordings; milliseconds, median and 90th
percentile over ``--rounds``. Printed; nothing is asserted.

    python -m bench.figures.smart_turn [--rounds 5]
"""

import argparse
import time
from typing import Callable, Dict, List

import numpy as np

from fixtures.noises import read_audio
from fixtures.pipecat_smart_turn import as_pipecat_pads, pipecats_features
from fixtures.recordings import ljspeech
from speech_event.recognizers.whisper.features import SAMPLE_RATE
from speech_event.turns.smart_turn import SmartTurn, smart_turn_features


def milliseconds(call: Callable[..., object], *arguments: object) -> float:
    began = time.perf_counter()
    call(*arguments)
    return 1000 * (time.perf_counter() - began)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rounds", type=int, default=5)
    rounds = parser.parse_args().rounds
    model, reference = SmartTurn(), pipecats_features()
    turns = [read_audio(recording.path, SAMPLE_RATE) for recording in ljspeech()]
    times: Dict[str, List[float]] = {"features (ours)": [], "features (pipecat)": [], "whole call": []}
    for _ in range(rounds):
        for audio in turns:
            times["features (ours)"].append(milliseconds(smart_turn_features, audio))
            padded = as_pipecat_pads(audio)
            times["features (pipecat)"].append(
                milliseconds(reference.compute_whisper_log_mel_features, padded)
            )
            times["whole call"].append(milliseconds(model.completion, audio))
    print(f"Smart Turn v3.2, {len(turns)} turns x {rounds} rounds, one thread")
    for name, each in times.items():
        median, p90 = np.percentile(each, [50, 90])
        print(f"  {name:<20} median {median:6.1f} ms   90th percentile {p90:6.1f} ms")


if __name__ == "__main__":
    main()
