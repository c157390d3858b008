"""What a grammar decision costs (python -m bench.figures.grammar_cost [--engines NAMES] [--gate]), issue 58.

Each utterance is said to a fresh node on the in-memory bus and the fake clock, as soundDetection
sends it (48 kHz blocks of 4096 samples, one after the other), with each grammar in turn: none,
``yes|no``, the robot's 32 commands (harness/data/robot_commands.txt) and 100 phrases (the commands,
57 sentences of bench/data/out_of_grammar.txt and eleven "go to table N"); speculation on (the
default) and off. Partial results are off. The speech:
- people, accepted: Speech Commands' development clips of "yes", "no" and "stop" (three of each),
  0.5 s of room noise (pink, -50 dBFS) before and after; in ``yes|no`` only yes and no are phrases;
- people, rejected: their clips of the ten digits (one of each), alike; no grammar holds a digit;
- voice, accepted: festival's slt saying eight of the commands (not in ``yes|no``: rejected there);
- voice, rejected: slt saying the last eight sentences of out_of_grammar.txt.
With no grammar every utterance is free speech, and "accepted" means a text was published.

Per engine, grammar, set and speculation setting: CPU seconds of the process per second of audio
said (the fake clock's executor runs every recognition on this thread, and onnxruntime's threads
count too), the wall time per utterance, transcriptions per utterance, speculations started and
thrown away, and for Whisper where the CPU went: encoder, free decoding, phrase scoring, the
evidence against silence. Each speculation runs to its end on the fake clock (none is stopped by
the next block), which is the work a node does when recognition is fast against the blocks.

With ``--gate``: the same on the wall clock and the thread executor, each utterance played in real
time behind the robot's gate (the blocks whose RMS reaches soundDetection's intensityThreshold, at
their times), a block stopping the speculation it makes worthless: what the node really runs.
Printed; nothing is asserted. Needs an idle machine.
"""

import argparse
import contextlib
import dataclasses
import time
from typing import Any, Callable, Dict, Iterator, List, Sequence, Tuple

import numpy as np

from bench.figures.end_of_speech import after_each_other, gated, played_in_real_time, played_on_fake_clock
from bench.figures.grammar import DIGITS, ENGINES, OUT_OF_GRAMMAR, RATE, in_the_room, lines
from bench.figures.measures import robot_commands
from fixtures.festival import speak_festival
from fixtures.noises import read_audio
from fixtures.recordings import SPEECH_COMMANDS
from harness.catalog import ScenarioEngines
from speech_event.config import SpeechEventConfig
from speech_event.ports import Recognizer, Transcript
from speech_event.recognizers.whisper import forced, model, recognizer
from speech_event.topics import SPEECH_NOT_RECOGNIZED

SAID_COMMANDS = (
    "go to the kitchen",
    "turn left",
    "stop",
    "what time is it",
    "open the door",
    "tell me a joke",
    "sit down",
    "hello pepper",
)
# "go to table N" for these N: the hundredth phrases
TABLES: Tuple[str, ...] = ("eleven", "twelve", "thirteen", "fourteen", "fifteen", "sixteen", "seventeen")
TABLES += ("eighteen", "nineteen", "twenty", "twenty one")
MARGIN = 0.5


def grammars() -> Dict[str, str]:
    """The grammars by name, as set_grammar takes them ("" is free speech)."""
    commands, others = robot_commands(), lines(OUT_OF_GRAMMAR)
    hundred = commands + others[:-8] + [f"go to table {number}" for number in TABLES]
    assert len(set(hundred)) == 100, len(set(hundred))
    return {
        "none": "",
        "yes|no": "yes|no",
        "32 commands": "|".join(commands),
        "100 phrases": "|".join(hundred),
    }


def speech_sets() -> Dict[str, List[Tuple[str, np.ndarray]]]:
    """Each set's utterances: (what was said, the audio at RATE)."""

    def clips(word: str, count: int) -> List[Tuple[str, np.ndarray]]:
        paths = sorted((SPEECH_COMMANDS / word).glob("*.wav"))[:count]
        return [(word, in_the_room(read_audio(path, RATE), MARGIN, path.name)) for path in paths]

    def voiced(phrases: Sequence[str]) -> List[Tuple[str, np.ndarray]]:
        return [
            (phrase, in_the_room(speak_festival(phrase, "slt", RATE), MARGIN, phrase)) for phrase in phrases
        ]

    return {
        "people, accepted": [said for word in ("yes", "no", "stop") for said in clips(word, 3)],
        "people, rejected": [said for digit in DIGITS for said in clips(digit, 1)],
        "voice, accepted": voiced(SAID_COMMANDS),
        "voice, rejected": voiced(lines(OUT_OF_GRAMMAR)[-8:]),
    }


class WhereTheTimeGoes:
    """CPU seconds of the Whisper engine's parts, while ``counting()``: the functions wrapped
    where the recognizer calls them, so that nothing in speech_event knows of the bench."""

    PARTS = {
        "encoder": (model.WhisperModel, "encode"),
        "free decoding": (recognizer, "whisper_greedy"),
        "phrase scoring": (recognizer, "score_phrases_that_decide"),
        "evidence": (forced.UnheardScores, "__call__"),
    }

    def __init__(self) -> None:
        self.seconds: Dict[str, float] = {}
        self.transcriptions = 0

    @contextlib.contextmanager
    def counting(self, engine: Recognizer) -> Iterator[None]:
        wrapped = [(owner, name, getattr(owner, name)) for owner, name in self.PARTS.values()]
        transcribe = engine.transcribe
        for part, (owner, name, function) in zip(self.PARTS, wrapped):
            setattr(owner, name, self._timed(part, function))

        def counted(audio: np.ndarray) -> Transcript:
            self.transcriptions += 1
            return transcribe(audio)

        engine.transcribe = counted  # type: ignore[method-assign]
        try:
            yield
        finally:
            for owner, name, function in wrapped:
                setattr(owner, name, function)
            del engine.transcribe  # the class's again

    def _timed(self, part: str, function: Callable[..., Any]) -> Callable[..., Any]:
        def timed(*args: object, **kwargs: object) -> Any:
            began = time.process_time()
            try:
                return function(*args, **kwargs)
            finally:
                self.seconds[part] = self.seconds.get(part, 0.0) + time.process_time() - began

        return timed


@dataclasses.dataclass
class Figures:
    audio: float = 0.0
    cpu: float = 0.0
    wall: float = 0.0
    utterances: int = 0
    accepted: int = 0
    started: int = 0
    used: int = 0


def measure(
    engine: Recognizer,
    config: SpeechEventConfig,
    grammar: str,
    speech: List[Tuple[str, np.ndarray]],
    gate: bool,
) -> Figures:
    figures = Figures()
    for _, audio in speech:
        began_cpu, began_wall = time.process_time(), time.perf_counter()
        if gate:
            texts, node = played_in_real_time(engine, config, gated(audio), grammar)
        else:
            steps = after_each_other(
                [((start + 4096) / RATE, audio[start : start + 4096]) for start in range(0, audio.size, 4096)]
            )
            texts, node = played_on_fake_clock(engine, config, steps, grammar)
        figures.cpu += time.process_time() - began_cpu
        figures.wall += time.perf_counter() - began_wall
        figures.audio += audio.size / RATE
        figures.utterances += 1
        figures.accepted += any(text != SPEECH_NOT_RECOGNIZED for text in texts)
        figures.started += node.speculations.started
        figures.used += node.speculations.used
    return figures


def measured(
    engine: Recognizer,
    config: SpeechEventConfig,
    grammar: str,
    speech: List[Tuple[str, np.ndarray]],
    gate: bool,
) -> str:
    """One line of figures for ``speech`` said to ``engine`` with ``config`` and ``grammar``."""
    parts = WhereTheTimeGoes()
    with parts.counting(engine):
        figures = measure(engine, config, grammar, speech, gate)
    line = (
        f"{figures.cpu / figures.audio:.3f} CPU s per s of audio, "
        f"{figures.wall / figures.utterances:.2f} s wall an utterance, "
        f"{parts.transcriptions / figures.utterances:.1f} transcriptions an utterance, "
        f"accepted {figures.accepted}/{figures.utterances}, speculations {figures.started} started, "
        f"{figures.started - figures.used} thrown away"
    )
    breakdown = ", ".join(f"{part} {seconds / figures.audio:.3f}" for part, seconds in parts.seconds.items())
    return line + (f"; CPU s per s: {breakdown}" if breakdown else "")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engines", default="tiny.en int8", help=f"comma-separated, of {', '.join(ENGINES)}")
    parser.add_argument("--gate", action="store_true", help="in real time behind the robot's gate")
    arguments = parser.parse_args()
    sets = speech_sets()
    for engine_name in arguments.engines.split(","):
        name, quantization = ENGINES[engine_name.strip()]
        base = SpeechEventConfig(
            partial_period=0.0, health_check_period=3600.0, quantization=quantization or "none"
        )
        with ScenarioEngines(name, base) as engines:
            engine = engines.build()
            engine.transcribe(sets["people, accepted"][0][1])  # loaded and warm
            print(f"{engine_name} ({'real time behind the gate' if arguments.gate else 'fake clock'})")
            for grammar_name, grammar in grammars().items():
                for set_name, speech in sets.items():
                    for speculating in (True, False):
                        config = dataclasses.replace(base, speculative_recognition=speculating)
                        label = (
                            f"{grammar_name:<11} {set_name:<16} speculation {'on ' if speculating else 'off'}"
                        )
                        print(
                            f"  {label}: {measured(engine, config, grammar, speech, arguments.gate)}",
                            flush=True,
                        )


if __name__ == "__main__":
    main()
