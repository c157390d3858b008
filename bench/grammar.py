"""Grammar mode: commands published, speech outside the grammar rejected (python -m bench.grammar),
issue 19. Targets: out-of-grammar speech published as a phrase at most 2 %, commands published
exactly at least 95 %, on both sets.

pocketsphinx (speech_event/recognizers/sphinx.py), on two sets:
(a) the tts voice (espeak-ng, fixtures/tts.py): the robot's commands (harness/data/robot_commands.txt)
    in their grammar, and the sentences of bench/data/out_of_grammar.txt (near misses of the
    commands and everyday speech) against the same grammar;
(b) real recordings, Debian's pocketsphinx-testdata: the cards recordings against cards.gram
    (expected: their transcription) and the librivox ones against cards.gram (none is in it).

For each set: in-grammar speech published exactly / rejected / published as another phrase, and
out-of-grammar speech published as a phrase (%); the ratio the engine judges by (nats: the
grammar's best path against the free decoding, recognizers/sphinx.py) as min / median / max for
in- and out-of-grammar speech that reached a whole phrase, so the threshold's place is visible; and
the decode time per second of audio with and without rejection (the free decoding is the
difference). Measured on whatever machine runs it; figures are printed, nothing is asserted.
"""

import argparse
import statistics
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import List, Optional, Sequence, Tuple

import numpy as np

from fixtures import recordings
from fixtures.tts import speak_tts
from speech_event.grammar import Grammar, load_grammar
from speech_event.recognizers.sphinx import DEFAULT_GRAMMAR_THRESHOLD, SphinxRecognizer

ROOT = Path(__file__).resolve().parents[1]
COMMANDS = ROOT / "harness" / "data" / "robot_commands.txt"
OUT_OF_GRAMMAR = ROOT / "bench" / "data" / "out_of_grammar.txt"
RATE = 16000

# (expected phrase, or None for speech outside the grammar; audio at 16 kHz)
Sample = Tuple[Optional[str], np.ndarray]


@dataclass
class Tally:
    """What one set's utterances came out as."""

    exact: int = 0
    rejected: int = 0
    wrong: int = 0
    in_count: int = 0
    published_out: int = 0
    out_count: int = 0
    in_ratios: List[float] = field(default_factory=list)
    out_ratios: List[float] = field(default_factory=list)
    wrong_examples: List[str] = field(default_factory=list)
    published_examples: List[str] = field(default_factory=list)


def lines(path: Path) -> List[str]:
    """The non-comment lines of a file, one phrase or sentence each."""
    return [
        line.strip() for line in path.read_text().splitlines() if line.strip() and not line.startswith("#")
    ]


def judge(recognizer: SphinxRecognizer, samples: Sequence[Sample]) -> Tuple[Tally, float]:
    """The set's tally, and the decode time per second of audio."""
    tally = Tally()
    busy = seconds = 0.0
    for expected, audio in samples:
        start = time.perf_counter()
        transcript = recognizer.transcribe(audio)
        busy += time.perf_counter() - start
        seconds += audio.size / RATE
        ratio = recognizer.last_ratio
        if expected is not None:
            tally.in_count += 1
            if ratio is not None:
                tally.in_ratios.append(ratio)
            if transcript.text == expected:
                tally.exact += 1
            elif transcript.text:
                tally.wrong += 1
                tally.wrong_examples.append(f"{expected!r} as {transcript.text!r}")
            else:
                tally.rejected += 1
        else:
            tally.out_count += 1
            if ratio is not None:
                tally.out_ratios.append(ratio)
            if transcript.text:
                tally.published_out += 1
                judged = "" if ratio is None else f" ({ratio:.0f})"
                tally.published_examples.append(f"as {transcript.text!r}{judged}")
    return tally, busy / seconds


def spread(values: List[float]) -> str:
    if not values:
        return "none reached a phrase"
    return f"min {min(values):.0f} / median {statistics.median(values):.0f} / max {max(values):.0f}"


def percent(count: int, total: int) -> str:
    return f"{100.0 * count / total:.1f} %" if total else "-"


def report(name: str, grammar: Grammar, samples: Sequence[Sample], threshold: float) -> None:
    """One set's figures, with rejection at ``threshold`` and without."""
    tally, rtf = judge(SphinxRecognizer(grammar, grammar_threshold=threshold), samples)
    without, rtf_without = judge(SphinxRecognizer(grammar, grammar_threshold=-float("inf")), samples)
    print(f"{name} (threshold {threshold:g} nats):")
    print(
        f"  in grammar ({tally.in_count}): published exactly {percent(tally.exact, tally.in_count)}, "
        f"rejected {percent(tally.rejected, tally.in_count)}, "
        f"published wrong {percent(tally.wrong, tally.in_count)}"
    )
    print(
        f"  out of grammar ({tally.out_count}): published as a phrase "
        f"{percent(tally.published_out, tally.out_count)}"
    )
    print(f"  ratio, in grammar ({len(tally.in_ratios)} reached a phrase): {spread(tally.in_ratios)}")
    print(f"  ratio, out of grammar ({len(tally.out_ratios)} reached a phrase): {spread(tally.out_ratios)}")
    near = sorted(tally.in_ratios)[:3], sorted(tally.out_ratios)[-3:]
    print(f"  nearest the threshold: in {[round(r) for r in near[0]]}, out {[round(r) for r in near[1]]}")
    for example in tally.wrong_examples + tally.published_examples:
        print(f"    {example}")
    print(
        f"  without rejection: in grammar published exactly {percent(without.exact, without.in_count)}, "
        f"out of grammar published {percent(without.published_out, without.out_count)}"
    )
    print(f"  decode time per second of audio: {rtf:.3f} with rejection, {rtf_without:.3f} without")


def tts_set() -> Tuple[Grammar, List[Sample]]:
    commands = lines(COMMANDS)
    samples: List[Sample] = [(command, speak_tts(command, RATE)) for command in commands]
    samples += [(None, speak_tts(sentence, RATE)) for sentence in lines(OUT_OF_GRAMMAR)]
    return load_grammar(COMMANDS), samples


def recorded_set() -> Optional[Tuple[Grammar, List[Sample]]]:
    if not recordings.CARDS_GRAMMAR.is_file() or not recordings.LIBRIVOX.is_dir():
        return None
    samples: List[Sample] = [(recording.text, recording.samples()) for recording in recordings.cards()]
    samples += [(None, recording.samples()) for recording in recordings.librivox()]
    return load_grammar(recordings.CARDS_GRAMMAR), samples


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--threshold", type=float, default=DEFAULT_GRAMMAR_THRESHOLD, help="the grammar_threshold to judge by"
    )
    arguments = parser.parse_args()
    grammar, samples = tts_set()
    report(f"(a) tts voice, {COMMANDS.name}", grammar, samples, arguments.threshold)
    recorded = recorded_set()
    if recorded is None:
        print("(b) recorded speech: skipped, apt-get install pocketsphinx-testdata")
        return
    report("(b) recorded speech, cards.gram: cards in it, librivox out of it", *recorded, arguments.threshold)


if __name__ == "__main__":
    main()
