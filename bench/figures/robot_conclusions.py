"""What the robot concludes from people's speech in free speech (python -m bench.figures.robot_conclusions),
issue 57 item 5: each recording through the node as the robot's soundDetection sends it (48 kHz
blocks on the in-memory bus, the robot's configuration: no grammar, text_style robot), then the
Behaviour Controller's own rule (harness/behaviour_controller.py) applied to what the node
published and to what was said.

Per engine and set: right (the robot concludes what the words said mean to it), wrong (a yes or a
no nobody said), missed (a yes or no said and nothing, or the other, concluded). Sets, each word
with 0.5 s of quiet room noise (pink, -50 dBFS) before and after: FSDD's development speakers
(george, jackson, lucas; TAKES of each digit), the Speech Commands clips of
tests/recordings/speech_commands (none of the held-out test files; "yes", "no" and "go" among
them: "go" is one of the controller's yes words), and the LJ Speech readings. Printed; nothing is
asserted. Speculation and partial results are off: the texts are the same with them.

    python -m bench.figures.robot_conclusions [--engines "tiny.en int8,base int8,pocketsphinx"] [--takes 1]
        [--text-style robot|engine]

``--text-style engine`` measures the node as it was before text_style: the engines' own writing.
"""

import argparse
import dataclasses
import logging
from dataclasses import dataclass, field
from typing import Dict, List, Sequence, Tuple

import numpy as np

from bench.figures.grammar import RATE, SPEAKERS, NodeRun, engine_config, in_the_room, people
from fixtures.noises import read_audio
from fixtures.recordings import SPEECH_COMMANDS, ljspeech
from harness.behaviour_controller import NO, YES, conclusion
from harness.catalog import ScenarioEngines
from speech_event.config import TEXT_STYLES
from speech_event.spelling import robot_written
from speech_event.topics import SPEECH_NOT_RECOGNIZED

MARGIN = 0.5  # seconds of room noise around each word
# (what was said, the audio at RATE)
Said = Tuple[str, np.ndarray]


@dataclass
class Conclusions:
    """How one set came out."""

    clips: int = 0
    right: int = 0
    wrong: int = 0  # a yes or no nobody said
    answers: int = 0  # yes or no said
    missed: int = 0  # of those, not concluded
    examples: List[str] = field(default_factory=list)

    def add(self, said: str, published: str) -> None:
        """One clip: what was said (as the robot's model would write it) and what was published."""
        meant, concluded = conclusion(robot_written(said)), conclusion(published)
        self.clips += 1
        self.right += concluded == meant
        if meant in (YES, NO):
            self.answers += 1
            self.missed += concluded != meant
        if concluded in (YES, NO) and concluded != meant:
            self.wrong += 1
        if concluded != meant and len(self.examples) < 6:
            self.examples.append(f"{said!r} -> {published!r}")

    def line(self, name: str) -> str:
        missed = f"{self.missed} of {self.answers}" if self.answers else "-"
        wrong = f"{self.wrong} ({100 * self.wrong / max(self.clips, 1):.1f} %)"
        return f"  {name:<16} {self.clips:>4} clips  right {self.right:>4}  wrong {wrong:<11} missed {missed}"


def speech_commands() -> List[Said]:
    return [
        (path.parent.name, in_the_room(read_audio(path, RATE), MARGIN, path.name))
        for path in sorted(SPEECH_COMMANDS.glob("*/*.wav"))
    ]


def fsdd(takes: int) -> List[Said]:
    return [said for speaker in SPEAKERS for said in people(speaker, takes, MARGIN)]


def readings() -> List[Said]:
    return [
        (recording.text, in_the_room(read_audio(recording.path, RATE), MARGIN, recording.name))
        for recording in ljspeech()
    ]


def conclusions(name: str, sets: Dict[str, Sequence[Said]], text_style: str) -> Dict[str, Conclusions]:
    recognizer, config = engine_config(name)
    config = dataclasses.replace(config, publish_unrecognized=False, text_style=text_style)
    tallies: Dict[str, Conclusions] = {}
    with ScenarioEngines(recognizer, config, simulated=True) as engines:
        run = NodeRun(engines.build(), config)
        for set_name, said in sets.items():
            tally = tallies.setdefault(set_name, Conclusions())
            for words, audio in said:
                published = run.say(audio)
                tally.add(words, "" if published == SPEECH_NOT_RECOGNIZED else published)
    return tallies


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engines", default="tiny.en int8,base int8,pocketsphinx")
    parser.add_argument("--takes", type=int, default=1, help="FSDD recordings of each digit a speaker")
    parser.add_argument("--text-style", choices=TEXT_STYLES, default="robot")
    arguments = parser.parse_args()
    logging.getLogger("speech_event").setLevel(logging.ERROR)  # clipped peaks: not what is measured
    sets: Dict[str, Sequence[Said]] = {
        "FSDD digits": fsdd(arguments.takes),
        "Speech Commands": speech_commands(),
        "LJ Speech": readings(),
    }
    for name in arguments.engines.split(","):
        print(f"{name} (free speech, text_style {arguments.text_style}):")
        totals = Conclusions()
        for set_name, tally in conclusions(name.strip(), sets, arguments.text_style).items():
            print(tally.line(set_name))
            for example in tally.examples:
                print(f"      {example}")
            for key in ("clips", "right", "wrong", "answers", "missed"):
                setattr(totals, key, getattr(totals, key) + getattr(tally, key))
        print(totals.line("all"), flush=True)


if __name__ == "__main__":
    main()
