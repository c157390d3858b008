"""Grammar mode through the node (python -m bench.figures.grammar), issues 19 and 32: commands published,
speech outside the grammar rejected, on every engine, voice and recording set.

Targets (issue 32): out-of-grammar speech published as a phrase in 2 % of cases or fewer, a command
published as another command in none; commands published exactly in 95 % or more in festival's
voices, and in espeak-ng's at least every command whose free decoding is already right.

Each utterance goes through the node as the robot's would: soundDetection's 4096-sample blocks at
48 kHz on the in-memory bus, validated, assembled, resampled, screened, transcribed, and what the
node publishes read off /speechEvent/text (``publish_unrecognized``: a rejection publishes
``Error: speech not recognized``, so every utterance answers). Speculation and partial results are
off: the texts are the same with them (tests/test_every_scenario.py), and the engine's last
grammar decision is then the final one's, whose ratio is reported.

Sets:
(a) the robot's 32 commands (harness/data/robot_commands.txt) and the 65 sentences of
    bench/data/out_of_grammar.txt (a third near misses), against the commands, in each voice:
    espeak-ng (tts) and festival's slt, kal and ked (fixtures/festival.py);
(b) Debian's pocketsphinx-testdata: the 5 cards against cards.gram (pocketsphinx) or a grammar of
    their 5 phrases and the 32 commands (the neural engines, which score every sentence); the 5
    librivox sentences against the same grammar (none is in it), and against no grammar (each
    must be published).
(c) with ``--people TAKES``: people saying digits (tests/recordings/fsdd: george, jackson, lucas;
    TAKES recordings of each digit, 1 to 5), per speaker, the word alone and with 0.2 and 1 s of
    room noise (pink, -50 dBFS) before and after it, as soundDetection sends it: against a digits
    grammar (exact / another digit / rejected), the robot's commands and yes|no (a digit is
    outside both), and no grammar (the digit written, in words or figures); Speech Commands' digits
    (16 kHz, 19 speakers) against the digits grammar, by the speakers' likely voice (women, men:
    bench/figures/speaker_pitch.py); people saying single words (tests/recordings/speech_commands, 16 kHz,
    33 speakers) with the same margins against the commands and yes|no: 'yes', 'no', 'stop' exact,
    the other words ('left', 'go', 'up', 'bird', 'seven', ...) published as nothing, and those
    words with pink noise and with babble 10 dB under them (0.2 s margin) against the commands;
    then 30 s of pink noise and of babble alone at -30 dBFS against the commands (nothing may be
    published).

Per engine and set: commands published exactly / rejected / as another command; out-of-grammar
speech published as a phrase; the ratio the engine judged by (nats: the most likely phrase
against the free decoding) as min / median / max for commands and for other speech; the
nearest cases; and the decoding time per second of audio. Printed; nothing is asserted.

``--record FILE`` writes each decision (for the neural engines the free decoding, every phrase's
score and, for Whisper, the evidence of the free text's phrase, or of the phrases
evidence_candidates names when the words took none: a replay with a wider slack than the record's
lacks the rest); ``--replay FILE`` judges those again with today's rule, decoding nothing: how a
change of the rule (onnx/grammar_choice.py) is measured on the same figures in seconds, not hours.
Whisper's scores below least_deciding_score are upper bounds (forced.score_phrases_that_decide
left those forms unscored): a rule that reaches below it lowers least_deciding_score too, and is
measured on a new record.
"""

import argparse
import contextlib
import json
import statistics
import time
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Dict, List, Optional, Protocol, Sequence, TextIO, Tuple, runtime_checkable

import numpy as np

from bench.figures.measures import robot_commands
from bench.figures.speaker_pitch import speech_commands_voices
from fixtures import recordings
from fixtures.festival import VOICES as FESTIVAL_VOICES
from fixtures.festival import festival_voice
from fixtures.noises import at_level, read_audio, under
from fixtures.recordings import FSDD, SPEECH_COMMANDS
from fixtures.tts import speak_tts
from harness.catalog import BASE, TINY_EN, ScenarioEngines
from harness.cli import COMMANDS
from speech_event.adapters.executors import ClockExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.config import SpeechEventConfig
from speech_event.interfaces.services import SET_GRAMMAR_SERVICE
from speech_event.messages import Float32MultiArray, SetGrammarRequest, String
from speech_event.node import SpeechEventNode
from speech_event.pipeline.resample import resample
from speech_event.ports import Recognizer
from speech_event.recognizers.nemo.recognizer import NemoRecognizer
from speech_event.recognizers.onnx.grammar_choice import NEURAL_GRAMMAR_THRESHOLD, GrammarChoice
from speech_event.recognizers.whisper.recognizer import WhisperRecognizer
from speech_event.topics import SIGNAL_TOPIC, SPEECH_NOT_RECOGNIZED, TEXT_TOPIC

ROOT = Path(__file__).resolve().parents[2]
OUT_OF_GRAMMAR = ROOT / "bench" / "data" / "out_of_grammar.txt"
RATE = 48000  # what soundDetection publishes
BLOCK = 4096
VOICES: Dict[str, Callable[[str, int], np.ndarray]] = {
    "tts": speak_tts,
    **{name: festival_voice(name) for name in FESTIVAL_VOICES},
}
# recognizer name (harness/catalog.py) and configuration lines, by the name printed
ENGINES: Dict[str, Tuple[str, str]] = {
    "pocketsphinx": ("pocketsphinx", ""),
    "tiny.en": (TINY_EN, ""),
    "tiny.en int8": (TINY_EN, "int8"),
    "base": (BASE, ""),
    "base int8": (BASE, "int8"),
}

# (expected phrase: None for speech outside the grammar, "" for any text; audio at RATE)
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
    examples: List[str] = field(default_factory=list)
    seconds: float = 0.0  # of audio
    busy: float = 0.0  # engine time


def lines(path: Path) -> List[str]:
    """The non-comment lines of a file, one phrase or sentence each."""
    return [
        line.strip() for line in path.read_text().splitlines() if line.strip() and not line.startswith("#")
    ]


@runtime_checkable
class JudgedByRatio(Protocol):
    """pocketsphinx (in its process or another): the ratio its last transcribe judged by."""

    @property
    def last_ratio(self) -> Optional[float]: ...


def ratio_of(engine: Recognizer) -> Optional[float]:
    """The ratio the engine's last transcribe within a grammar judged by (the most likely phrase
    against the free decoding), when it judged one."""
    if isinstance(engine, (NemoRecognizer, WhisperRecognizer)):
        choice = engine.last_choice
        return None if choice is None else best_ratio(choice)
    return engine.last_ratio if isinstance(engine, JudgedByRatio) else None


def best_ratio(choice: GrammarChoice) -> float:
    """The ratio of a neural decision's most likely phrase against its free decoding."""
    return choice.ratio(max(choice.phrase_scores, key=choice.phrase_scores.__getitem__))


class NodeRun:
    """One node on the in-memory bus and a fake clock, fed one utterance at a time."""

    def __init__(self, engine: Recognizer, config: SpeechEventConfig) -> None:
        self.engine = engine
        self._clock = FakeClock()
        self._bus = InMemoryBus()
        self._texts: List[str] = []
        self._bus.subscribe(TEXT_TOPIC, String, lambda message: self._texts.append(message.data))  # type: ignore[attr-defined]
        self._node = SpeechEventNode(config, self._bus, self._clock, engine, ClockExecutor(self._clock))
        self._signal = self._bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
        self._pause = config.speech_pause_period
        self._node.start()

    def use_grammar(self, grammar: str) -> None:
        """set_grammar, as the Behaviour Controller calls it: a file, phrases parted by |, or ''."""
        response = self._bus.call(SET_GRAMMAR_SERVICE, SetGrammarRequest(grammar))
        assert response.response == 1, f"set_grammar {grammar[:60]!r} refused"  # type: ignore[attr-defined]

    def say(self, audio: np.ndarray) -> str:
        """What the node publishes for ``audio`` (at RATE): a text, or SPEECH_NOT_RECOGNIZED."""
        said = self.heard(audio)
        return said[0] if said else SPEECH_NOT_RECOGNIZED

    def heard(self, audio: np.ndarray) -> List[str]:
        """Every text the node publishes for ``audio`` (at RATE), which may be cut in utterances."""
        before = len(self._texts)
        start = self._clock.now()
        padded = np.concatenate([audio, np.zeros(-audio.size % BLOCK, np.float32)])
        for index in range(0, padded.size, BLOCK):
            self._clock.advance_to(start + (index + BLOCK) / RATE)
            self._signal.publish(Float32MultiArray(data=padded[index : index + BLOCK]))
        self._clock.advance(self._pause + 0.5)
        return self._texts[before:]


def decision(engine: Recognizer) -> Dict[str, object]:
    """The engine's last grammar decision as --record writes it: every phrase's score for the neural
    engines (so that other rules can be tried on the same figures), the ratio for pocketsphinx."""
    if isinstance(engine, (NemoRecognizer, WhisperRecognizer)) and engine.last_choice is not None:
        choice = engine.last_choice
        return {
            "free": choice.free_text,
            "free_score": choice.free_score,
            "scores": choice.phrase_scores,
            "evidence": dict(choice.evidence),
        }
    return {"ratio": ratio_of(engine)}


def judge(run: NodeRun, samples: Sequence[Sample], record: Optional[TextIO] = None, label: str = "") -> Tally:
    """The set's tally through the node; each utterance written to ``record`` (JSON lines)."""
    tally = Tally()
    for expected, audio in samples:
        began = time.perf_counter()
        text = run.say(audio)
        tally.busy += time.perf_counter() - began
        tally.seconds += audio.size / RATE
        published = "" if text == SPEECH_NOT_RECOGNIZED else text
        if record is not None:
            line = {"set": label, "expected": expected, "published": published, **decision(run.engine)}
            record.write(json.dumps(line) + "\n")
        count(tally, expected, published, ratio_of(run.engine))
    return tally


def count(tally: Tally, expected: Optional[str], published: str, ratio: Optional[float]) -> None:
    """One utterance's outcome in its set's tally."""
    if expected is not None:
        tally.in_count += 1
        if ratio is not None:
            tally.in_ratios.append(ratio)
        if published == expected or (expected == "" and published):
            tally.exact += 1
        elif published:
            tally.wrong += 1
            tally.examples.append(f"said {expected!r}, published {published!r}")
        else:
            tally.rejected += 1
    else:
        tally.out_count += 1
        if ratio is not None:
            tally.out_ratios.append(ratio)
        if published:
            tally.published_out += 1
            tally.examples.append(f"outside the grammar, published {published!r} ({ratio})")


def replay(record: Path) -> None:
    """Judge a --record run's neural decisions again with the rule of today's
    onnx/grammar_choice.py: the free decoding and every phrase's score are what the engine computed
    then, so a new rule is measured on the same figures without decoding again. pocketsphinx's
    lines hold its ratio alone (a rejection names no phrase): they are left out."""
    tallies: Dict[str, Tally] = {}
    for line in record.read_text().splitlines():
        decided = json.loads(line)
        if "scores" not in decided:
            continue
        choice = GrammarChoice(
            decided["free"], decided["free_score"], decided["scores"], decided.get("evidence", {})
        )
        published = choice.transcript(NEURAL_GRAMMAR_THRESHOLD).text
        count(tallies.setdefault(decided["set"], Tally()), decided["expected"], published, best_ratio(choice))
    for label, tally in tallies.items():
        report(label, tally)


def spread(values: List[float]) -> str:
    if not values:
        return "none judged"
    return f"{min(values):.1f} / {statistics.median(values):.1f} / {max(values):.1f}"


def percent(count: int, total: int) -> str:
    return f"{100.0 * count / total:.1f} %" if total else "-"


def report(name: str, tally: Tally) -> None:
    print(
        f"  {name}: commands ({tally.in_count}) exact {percent(tally.exact, tally.in_count)}, "
        f"rejected {percent(tally.rejected, tally.in_count)}, "
        f"as another {percent(tally.wrong, tally.in_count)}; "
        f"other speech ({tally.out_count}) published {percent(tally.published_out, tally.out_count)}; "
        f"ratio min/median/max: commands {spread(tally.in_ratios)}, other {spread(tally.out_ratios)}"
        + (f"; {tally.busy / tally.seconds:.3f} s a second of audio" if tally.seconds else "")
    )
    for example in tally.examples:
        print(f"      {example}")


def spoken_set(voice: str) -> List[Sample]:
    speak = VOICES[voice]
    samples: List[Sample] = [(command, speak(command, RATE)) for command in robot_commands()]
    return samples + [(None, speak(sentence, RATE)) for sentence in lines(OUT_OF_GRAMMAR)]


def recorded(
    said: Sequence[recordings.Recording], expected: Callable[[recordings.Recording], Optional[str]]
) -> List[Sample]:
    return [
        (expected(recording), resample(recording.samples(), recordings.SAMPLE_RATE, RATE))
        for recording in said
    ]


def cards_grammar(engine: str) -> str:
    """cards.gram for pocketsphinx; the neural engines score every sentence, so for them the five
    cards' phrases among the robot's commands."""
    if engine == "pocketsphinx":
        return str(recordings.CARDS_GRAMMAR)
    return "|".join([recording.text for recording in recordings.cards()] + robot_commands())


SPEAKERS = ("george", "jackson", "lucas")
DIGITS = ("zero", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine")
MARGINS = (0.0, 0.2, 1.0)
ROOM_DB = -50.0
NOISE_ALONE_DB = -30.0
# Issue 43: at this SNR no word outside the grammar may become a command.
NOISY_SNR_DB = 10.0


def engine_config(name: str) -> Tuple[str, SpeechEventConfig]:
    """The recognizer of ``name`` and the node's configuration for it: every utterance answers
    (publish_unrecognized), no speculation nor partial results (the texts are the same)."""
    recognizer, quantization = ENGINES[name]
    config = SpeechEventConfig(
        speculative_recognition=False,
        partial_period=0.0,
        publish_unrecognized=True,
        quantization=quantization or "none",
    )
    return recognizer, config


def in_the_room(speech: np.ndarray, margin: float, seed_name: str) -> np.ndarray:
    """``speech`` with ``margin`` seconds of room noise before and after, from a seed of its own."""
    rng = np.random.default_rng(zlib.crc32(seed_name.encode()))
    room = [at_level("pink", round(margin * RATE), ROOM_DB, RATE, rng) for _ in range(2)]
    return np.concatenate([room[0], speech, room[1]])


def people(speaker: str, takes: int, margin: float) -> List[Tuple[str, np.ndarray]]:
    """Each digit by ``speaker`` (``takes`` recordings of it) at RATE, ``margin`` seconds of room
    noise before and after, drawn from a seed of the recording's own."""
    said = []
    for digit, word in enumerate(DIGITS):
        for take in range(takes):
            name = f"{digit}_{speaker}_{take}"
            said.append((word, in_the_room(read_audio(FSDD / f"{name}.wav", RATE), margin, name)))
    return said


def people_words(margin: float, phrases: Sequence[str], noise: Optional[str] = None) -> List[Sample]:
    """Each Speech Commands clip, ``margin`` seconds of room noise before and after, ``noise``
    (pink, babble) NOISY_SNR_DB under it when given: a word that is one of ``phrases`` expected as
    itself, any other outside the grammar."""
    said: List[Sample] = []
    for path in sorted(SPEECH_COMMANDS.glob("*/*.wav")):
        word = path.parent.name
        audio = read_audio(path, RATE)
        if noise is not None:
            audio = under(
                audio, noise, NOISY_SNR_DB, RATE, np.random.default_rng(zlib.crc32(path.name.encode()))
            )
        said.append((word if word in phrases else None, in_the_room(audio, margin, path.name)))
    return said


def wideband_digits(margin: float, voices: Dict[str, str]) -> Dict[str, List[Sample]]:
    """Speech Commands' digits (16 kHz, 19 speakers), ``margin`` seconds of room noise before and
    after each, by their speaker's likely voice in ``voices`` (bench/figures/speaker_pitch.py)."""
    said: Dict[str, List[Sample]] = {}
    for digit in DIGITS:
        for path in sorted((SPEECH_COMMANDS / digit).glob("*.wav")):
            audio = in_the_room(read_audio(path, RATE), margin, path.name)
            said.setdefault(voices[path.stem.split("_")[0]], []).append((digit, audio))
    return said


def as_digit(text: str) -> str:
    """A free text as a digit's word when it is one digit, in words or figures ('Three.', '3')."""
    word = "".join(letter for letter in text.lower() if letter.isalnum())
    return DIGITS[int(word)] if word.isdigit() and len(word) == 1 else word


def run_people(name: str, takes: int, record: Optional[TextIO]) -> None:
    """Set (c)."""
    recognizer, config = engine_config(name)
    grammars = (
        ("digits", "|".join(DIGITS), True),
        ("commands", str(COMMANDS), False),
        ("yes|no", "yes|no", False),
    )
    print(f"{name}, people saying digits ({takes} of each by each speaker):")
    with ScenarioEngines(recognizer, config, simulated=True) as engines:
        run = NodeRun(engines.build(), config)
        for label, grammar, inside in grammars:
            run.use_grammar(grammar)
            for margin in MARGINS:
                for speaker in SPEAKERS:
                    said = [
                        (word if inside else None, audio) for word, audio in people(speaker, takes, margin)
                    ]
                    tally = judge(run, said, record, f"{name} {label} {speaker} {margin}")
                    report(f"(c) {label}, {speaker}, margin {margin} s", tally)
        run.use_grammar("|".join(DIGITS))
        voices = speech_commands_voices()
        for margin in MARGINS:
            for voice, said in sorted(wideband_digits(margin, voices).items()):
                tally = judge(run, said, record, f"{name} wideband digits {voice} {margin}")
                report(f"(c) digits, Speech Commands, likely {voice}, margin {margin} s", tally)
        run.use_grammar("")
        for margin in MARGINS:
            for speaker in SPEAKERS:
                tally = Tally()
                for word, audio in people(speaker, takes, margin):
                    count(tally, word, as_digit(run.say(audio)), None)
                report(f"(c) no grammar: the digit written, {speaker}, margin {margin} s", tally)
        for label, grammar, phrases in (
            ("commands", str(COMMANDS), robot_commands()),
            ("yes|no", "yes|no", ["yes", "no"]),
        ):
            run.use_grammar(grammar)
            for margin in MARGINS:
                tally = judge(run, people_words(margin, phrases), record, f"{name} words {label} {margin}")
                report(f"(c) single words against {label}, margin {margin} s", tally)
        run.use_grammar(str(COMMANDS))
        for kind in ("pink", "babble"):
            said = people_words(MARGINS[1], robot_commands(), kind)
            tally = judge(run, said, record, f"{name} words commands {kind} {NOISY_SNR_DB:.0f} dB")
            report(f"(c) single words against commands, {kind} noise {NOISY_SNR_DB:.0f} dB under them", tally)
        for kind in ("pink", "babble"):
            noise = at_level(kind, 30 * RATE, NOISE_ALONE_DB, RATE, np.random.default_rng(0))
            report(f"(c) {kind} noise alone, 30 s, against the commands", judge(run, [(None, noise)]))


def run_engine(name: str, voices: Sequence[str], record: Optional[TextIO]) -> None:
    recognizer, config = engine_config(name)
    print(f"{name}:")
    with ScenarioEngines(recognizer, config, simulated=True) as engines:
        run = NodeRun(engines.build(), config)
        run.use_grammar(str(COMMANDS))
        for voice in voices:
            report(f"(a) {voice}", judge(run, spoken_set(voice), record, f"{name} {voice}"))
        run.use_grammar(cards_grammar(name))
        cards = recorded(recordings.cards(), lambda recording: recording.text)
        cards += recorded(recordings.librivox(), lambda recording: None)
        tally = judge(run, cards, record, f"{name} cards")
        report("(b) recordings: cards in their grammar, librivox out of it", tally)
        run.use_grammar("")
        report(
            "(b) librivox, no grammar: published",
            judge(run, recorded(recordings.librivox(), lambda recording: "")),
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--engines", nargs="+", choices=sorted(ENGINES), default=list(ENGINES))
    parser.add_argument(
        "--voices", nargs="*", choices=sorted(VOICES), default=list(VOICES), help="none: the recordings only"
    )
    parser.add_argument(
        "--people",
        type=int,
        choices=range(1, 6),
        metavar="TAKES",
        help="set (c), TAKES of each digit (1 to 5)",
    )
    parser.add_argument("--record", type=Path, help="write each utterance's decision here (JSON lines)")
    parser.add_argument(
        "--replay", type=Path, help="judge a --record file's decisions again; nothing is decoded"
    )
    arguments = parser.parse_args()
    if arguments.replay:
        replay(arguments.replay)
        return
    with contextlib.ExitStack() as stack:
        record = stack.enter_context(open(arguments.record, "w")) if arguments.record else None
        for name in arguments.engines:
            if arguments.people:
                run_people(name, arguments.people, record)
            run_engine(name, arguments.voices, record)


if __name__ == "__main__":
    main()
