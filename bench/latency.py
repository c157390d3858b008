"""How soon the text comes after the speaker stops (python -m bench.latency [ENGINE ...]), issue 11.

(a) In memory, in real time (the wall clock, the thread executor): for each engine and utterances
    of 1, 3, 5 and 10 s, the time from the last block to the text at a subscriber, minus the
    pause (1.5 s), median and max of 3 runs, without and with speculative recognition. The blocks
    of an utterance are published at once (the latency counts from the last one); the speculation
    starts 0.3 s after it. Target with speculation: pause + 50 ms or less whenever recognition
    takes less than the pause minus the gap (1.2 s).
(b) Early end of turn (early_pause 0.5 s): "yes" in the tones voice, time from the last block to the
    text (target 0.5 s).
(c) Engine time spent on speculations that more speech made worthless, per hour of speech: 200
    utterances of 3 words with 0.4 to 0.8 s pauses between the words (each pause longer than the
    gap: a speculation starts and the next word discards it), on the fake clock with the engine
    run for real; every speculation runs to its end there, so this is the most it can cost.

Pocketsphinx cannot be stopped, and its texts depend on what it heard before, so the node does
not speculate with it: its two figures show that.
Engines: the fake (tones) recognizer, the NeMo engine on the tones fixture model, pocketsphinx
with a grammar and with its language model, and the large conformer: with
SPEECH_EVENT_LARGE_MODEL=DIR, the NeMo engine on the random-weight 119 M-parameter model that
bench/nemo_parity.py builds and exports (it needs NeMo; the exported directory is left in
/tmp/speech_event_parity_*/exported); without, a stand-in that takes that model's measured time
(real-time factor 0.22 on 2 cores), sleeping 0.22 s per second of audio, and stops when cancelled.
"""

import dataclasses
import os
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Callable, Dict, List, Tuple

import numpy as np

from fixtures.audio import speak_tones
from fixtures.tones_model import build_tones_model
from fixtures.tts import speak_tts
from harness.cli import COMMANDS
from speech_event import SIGNAL_TOPIC, TEXT_TOPIC
from speech_event.adapters.executors import ClockExecutor, ThreadExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.adapters.system_clock import SystemClock
from speech_event.config import SpeechEventConfig
from speech_event.grammar import load_grammar
from speech_event.messages import Float32MultiArray, String
from speech_event.node import SpeechEventNode
from speech_event.ports import Recognizer, Transcript
from speech_event.recognizers.nemo.recognizer import NemoRecognizer
from speech_event.recognizers.sphinx import SphinxRecognizer
from speech_event.recognizers.tones import ToneRecognizer

RATE = 48000
BLOCK = 4096
LENGTHS = (1.0, 3.0, 5.0, 10.0)
RUNS = 3
LARGE_RTF = 0.22


class LargeConformerStandIn:
    """Takes the large conformer's time (RTF 0.22) and answers nothing; cancel stops it."""

    sample_rate = 16000

    def __init__(self) -> None:
        self._cancelled = threading.Event()

    def transcribe(self, audio: np.ndarray) -> Transcript:
        self._cancelled.clear()
        if self._cancelled.wait(LARGE_RTF * audio.size / self.sample_rate):
            raise RuntimeError("cancelled")
        return Transcript("")

    def stop(self) -> None:
        self._cancelled.set()


def _speech(voice: str, seconds: float) -> np.ndarray:
    """About ``seconds`` of speech: phrases in the voice, one after another, cut to length."""
    lines = [line.strip() for line in COMMANDS.read_text().splitlines()]
    phrases = [line for line in lines if line and not line.startswith("#")]
    if voice != "tts":
        phrases = ["go to the kitchen please"]
    parts: List[np.ndarray] = []
    while sum(part.size for part in parts) < seconds * RATE:
        phrase = phrases[len(parts) % len(phrases)]
        parts.append(speak_tts(phrase, RATE) if voice == "tts" else speak_tones(phrase, RATE))
    return np.concatenate(parts)[: int(seconds * RATE)].astype(np.float32)


def _latency(recognizer: Recognizer, config: SpeechEventConfig, audio: np.ndarray) -> float:
    """Seconds from the last block to the text, in real time, minus the pause."""
    clock, bus, executor = SystemClock(), InMemoryBus(), ThreadExecutor()
    heard = threading.Event()
    arrived: List[float] = []

    def on_text(message: object) -> None:
        arrived.append(time.monotonic())
        heard.set()

    bus.subscribe(TEXT_TOPIC, String, on_text)
    quiet = dataclasses.replace(config, publish_unrecognized=True)  # every utterance publishes
    node = SpeechEventNode(quiet, bus, clock, recognizer, executor)
    sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    node.start()
    for start in range(0, audio.size, BLOCK):
        sound_detection.publish(Float32MultiArray(data=audio[start : start + BLOCK]))
    last_block = time.monotonic()
    heard.wait(60.0)
    node.stop()
    executor.shutdown(60.0)
    return arrived[0] - last_block - config.speech_pause_period


def _engines(work: Path) -> Dict[str, Tuple[Callable[[], Recognizer], str]]:
    """Every engine, or those whose names hold one of the words given on the command line."""
    grammar = load_grammar(COMMANDS)
    engines: Dict[str, Tuple[Callable[[], Recognizer], str]] = {
        "fake (tones)": (ToneRecognizer, "tones"),
        "NeMo engine, tones fixture model": (
            lambda: NemoRecognizer(build_tones_model(work / "tones")),
            "tones",
        ),
        "pocketsphinx grammar": (lambda: SphinxRecognizer(grammar=grammar), "tts"),
        "pocketsphinx language model": (SphinxRecognizer, "tts"),
        **_large_conformer(),
    }
    wanted = sys.argv[1:]
    return {name: engine for name, engine in engines.items() if not wanted or any(w in name for w in wanted)}


def _large_conformer() -> Dict[str, Tuple[Callable[[], Recognizer], str]]:
    exported = os.environ.get("SPEECH_EVENT_LARGE_MODEL")
    if exported:
        return {
            "large conformer (119 M, random weights)": (
                lambda: NemoRecognizer(Path(exported)),
                "tts",
            )
        }
    return {f"large conformer stand-in (RTF {LARGE_RTF})": (LargeConformerStandIn, "tones")}


def speculation_latency() -> None:
    plain = SpeechEventConfig(
        health_check_period=3600.0, speculative_recognition=False, max_utterance_length=30.0
    )
    speculating = dataclasses.replace(plain, speculative_recognition=True)
    with tempfile.TemporaryDirectory() as work:
        for name, (make, voice) in _engines(Path(work)).items():
            recognizer = make()
            for seconds in LENGTHS:
                audio = _speech(voice, seconds)
                figures = []
                for config in (plain, speculating):
                    runs = [_latency(recognizer, config, audio) for _ in range(RUNS)]
                    figures.append(
                        f"median {1000 * statistics.median(runs):6.0f} ms, max {1000 * max(runs):6.0f} ms"
                    )
                print(f"(a) {name:42s} {seconds:4.0f} s: without {figures[0]}; with {figures[1]}", flush=True)


def early_end_of_turn() -> None:
    config = SpeechEventConfig(health_check_period=3600.0, early_pause=0.5)
    runs = [
        _latency(ToneRecognizer(), config, speak_tones("yes", RATE)) + config.speech_pause_period
        for _ in range(5)
    ]
    median = 1000 * statistics.median(runs)
    print(f"(b) early end of turn, 'yes': text {median:.0f} ms after the last block (median of 5)")


def wasted_speculation() -> None:
    rng = np.random.default_rng(0)
    with tempfile.TemporaryDirectory() as work:
        for name, (make, voice) in _engines(Path(work)).items():
            if "stand-in" in name:
                continue  # it computes nothing: its time is the clock's
            clock, bus = FakeClock(), InMemoryBus()
            node = SpeechEventNode(
                SpeechEventConfig(health_check_period=3600.0), bus, clock, make(), ClockExecutor(clock)
            )
            sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
            node.start()
            words = [_speech(voice, 0.6) for _ in range(5)]
            speech_seconds = 0.0
            for _ in range(200):
                for index in range(3):
                    word = words[int(rng.integers(len(words)))]
                    for start in range(0, word.size, BLOCK):
                        clock.advance(BLOCK / RATE)
                        sound_detection.publish(Float32MultiArray(data=word[start : start + BLOCK]))
                    speech_seconds += word.size / RATE
                    clock.advance(float(rng.uniform(0.4, 0.8)) if index < 2 else 2.0)
            node.stop()
            per_hour = node.speculations.wasted_seconds * 3600.0 / speech_seconds
            print(
                f"(c) {name:42s} speculations {node.speculations.started}, used {node.speculations.used}; "
                f"wasted engine time {per_hour:.1f} s per hour of speech"
            )


if __name__ == "__main__":
    speculation_latency()
    early_end_of_turn()
    wasted_speculation()
