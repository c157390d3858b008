"""Partial results (python -m bench.figures.partial [--roscore] [--runs N] [ENGINE ...]), issue 20.

The node runs in real time: soundDetection's blocks (4096 samples at 48 kHz) are published at the
pace they are recorded, 85 ms apart. In memory the node runs in this process on the wall clock with
its thread executor; with --roscore it is its own process on a roscore of the benchmark's own, and
the texts are timed where a subscriber gets them. For each engine and an utterance of 3 and of 10 s,
over --runs runs (3 by default) with partials off and as many with them on (partial_period 0.5):

- words: for each word of the final text, the delay from the block its sound ends in to the first
  partial whose words begin with the final's words up to it (median and max over every word of
  every run), and how many of the final's words no partial ever showed;
- partials: how many came for the utterance (median, and the fewest and most of a run);
- worker: the engine time the partial runs and feeds took, as a share of the utterance's length
  (median; on a roscore read from the node's /diagnostics);
- final: last block to the final text, minus the pause, with partials off and on, median and max
  (the target: no measurable difference, as closed utterances come first and a closing utterance
  cancels a run).

Word ends: the tones voice is concatenative (a word ends where the text up to it, spoken alone,
ends, less its trailing gap); espeak's (tts) is taken the same way, an approximation.
Engines: the fake (tones), the NeMo engine on the tones transducer, the Whisper engine on the tones
Whisper model, pocketsphinx with its language model (tts), and the large conformer as in
bench/figures/latency.py (SPEECH_EVENT_LARGE_MODEL=DIR; without it, in memory only, its stand-in that
answers nothing).
"""

import argparse
import contextlib
import dataclasses
import functools
import os
import statistics
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, ContextManager, Dict, Iterator, List, Optional, Tuple

import numpy as np

from bench.figures.latency import LARGE_RTF, LargeConformerStandIn
from fixtures.audio import normalise_text, speak_tones
from fixtures.tones_model import build_tones_model
from fixtures.tts import speak_tts
from fixtures.whisper_tones_model import build_whisper_tones_model
from speech_event import PARTIAL_TOPIC, SIGNAL_TOPIC, TEXT_TOPIC
from speech_event.adapters.executors import ThreadExecutor
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.adapters.system_clock import SystemClock
from speech_event.config import SpeechEventConfig, format_config
from speech_event.interfaces.diagnostics import DIAGNOSTICS_TOPIC, PARTIAL_WORKER_KEY
from speech_event.messages import DiagnosticArray, Float32MultiArray, String
from speech_event.node import SpeechEventNode
from speech_event.ports import Recognizer
from speech_event.recognizers import RECOGNIZERS
from speech_event.recognizers.nemo.manifest import CONFORMER_TRANSDUCER
from speech_event.recognizers.whisper.manifest import WHISPER

RATE = 48000
BLOCK = 4096
LENGTHS = (3.0, 10.0)
SENTENCE = "please go to the kitchen and bring me a glass of water then come back to the door"
Speak = Callable[[str, int], np.ndarray]
VOICES: Dict[str, Speak] = {"tones": speak_tones, "tts": speak_tts}
WORD_GAP = int(0.09 * RATE)  # the tones voice's trailing gap (fixtures/audio.py)
DIAGNOSTICS_PERIOD = 0.25  # s, the node's on a roscore


@dataclass(frozen=True)
class Utterance:
    audio: np.ndarray
    word_ends: List[int]  # the sample each word's sound ends at


@dataclass(frozen=True)
class Engine:
    """An engine as the node builds it from its configuration, in memory and on a roscore."""

    voice: str
    recognizer: str  # the node's --recognizer
    model: Optional[Callable[[Path], Path]] = None  # builds its model directory in a folder
    stand_in: Optional[Callable[[], Recognizer]] = None  # a stand-in that runs in memory only

    def config(self, base: SpeechEventConfig, model: Optional[Path]) -> SpeechEventConfig:
        """``base`` with this engine's family and its ``model`` directory (built by ``self.model``)."""
        return dataclasses.replace(base, en_model_path="" if model is None else str(model), model=self.family)

    @property
    def family(self) -> str:
        return WHISPER if self.recognizer == "whisper" else CONFORMER_TRANSDUCER


@dataclass(frozen=True)
class Run:
    final_latency: float  # last block to the final text, minus the pause
    final: str
    partials: List[Tuple[float, str]]
    block_times: List[float]
    partial_seconds: float  # engine time of partial runs and feeds


def _utterance(voice: str, seconds: float) -> Utterance:
    """Words of SENTENCE, again and again, as many as fit in ``seconds``."""
    speak, words = VOICES[voice], normalise_text(SENTENCE).split()
    said: List[str] = []
    ends: List[int] = []
    while True:
        text = " ".join([*said, words[len(said) % len(words)]])
        audio = speak(text, RATE)
        if audio.size > seconds * RATE and said:
            break
        said.append(words[len(said) % len(words)])
        ends.append(audio.size - (WORD_GAP if voice == "tones" else 0))
    return Utterance(speak(" ".join(said), RATE), ends)


def _paced(publish: Callable[[np.ndarray], None], audio: np.ndarray) -> List[float]:
    """Publishes ``audio`` block by block at the pace soundDetection records it; when each went."""
    block_times: List[float] = []
    began = time.monotonic()
    for number, start in enumerate(range(0, audio.size, BLOCK)):
        time.sleep(max(0.0, began + (number + 1) * BLOCK / RATE - time.monotonic()))
        publish(audio[start : start + BLOCK])
        block_times.append(time.monotonic())
    return block_times


class Heard:
    """What a subscriber got on the text and partial topics, with the wall clock's time."""

    def __init__(self) -> None:
        self.finals: List[Tuple[float, str]] = []
        self.partials: List[Tuple[float, str]] = []
        self.final = threading.Event()

    def on_text(self, message: object) -> None:
        self.finals.append((time.monotonic(), message.data))  # type: ignore[attr-defined]
        self.final.set()

    def on_partial(self, message: object) -> None:
        self.partials.append((time.monotonic(), message.data))  # type: ignore[attr-defined]

    def run(self, config: SpeechEventConfig, block_times: List[float], partial_seconds: float) -> Run:
        if not self.final.wait(120.0):
            raise TimeoutError("no final text in 120 s")
        at, text = self.finals[0]
        latency = at - block_times[-1] - config.speech_pause_period
        return Run(latency, text, self.partials, block_times, partial_seconds)


Play = Callable[[Utterance], Run]


def _send(publisher: Any, block: np.ndarray) -> None:
    publisher.publish(Float32MultiArray(data=block))


@contextlib.contextmanager
def in_memory(engine: Engine, config: SpeechEventConfig) -> Iterator[Play]:
    """The node in this process; one node per run, the engine built once."""
    recognizer = engine.stand_in() if engine.stand_in else RECOGNIZERS[engine.recognizer](config)

    def play(utterance: Utterance) -> Run:
        clock, bus, executor, heard = SystemClock(), InMemoryBus(), ThreadExecutor(), Heard()
        bus.subscribe(TEXT_TOPIC, String, heard.on_text)
        bus.subscribe(PARTIAL_TOPIC, String, heard.on_partial)
        node = SpeechEventNode(config, bus, clock, recognizer, executor)
        sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
        node.start()
        block_times = _paced(functools.partial(_send, sound_detection), utterance.audio)
        heard.final.wait(120.0)
        node.stop()
        executor.shutdown(120.0)
        return heard.run(config, block_times, node.partials.worker_seconds)

    yield play


class OnRoscore:
    """The node as its own process on the benchmark's roscore, one per engine and configuration."""

    def __init__(self, graph: Any) -> None:
        self._graph = graph
        self._heard = Heard()
        self._worker_seconds: List[float] = []  # the node's diagnostics, as they come
        graph.transport.subscribe(TEXT_TOPIC, String, lambda m: self._heard.on_text(m))
        graph.transport.subscribe(PARTIAL_TOPIC, String, lambda m: self._heard.on_partial(m))
        graph.transport.subscribe(DIAGNOSTICS_TOPIC, DiagnosticArray, self._on_diagnostics)

    def _on_diagnostics(self, message: Any) -> None:
        values = {value.key: value.value for value in message.status[0].values}
        self._worker_seconds.append(float(values[PARTIAL_WORKER_KEY]))

    @contextlib.contextmanager
    def __call__(self, engine: Engine, config: SpeechEventConfig) -> Iterator[Play]:
        # Diagnostics often enough to read the partials' worker time right after each final text.
        config = dataclasses.replace(config, health_check_period=DIAGNOSTICS_PERIOD)
        topics = (TEXT_TOPIC, PARTIAL_TOPIC, DIAGNOSTICS_TOPIC)
        node = self._graph.start_node(
            format_config(config),
            engine.recognizer,
            lambda: all(self._graph.subscribed(topic)() for topic in topics),
        )
        self._worker_seconds.clear()
        try:
            yield lambda utterance: self._play(config, utterance)
        finally:
            self._graph.stop_node(node)

    def _play(self, config: SpeechEventConfig, utterance: Utterance) -> Run:
        self._heard = Heard()
        before = self._worker_seconds[-1] if self._worker_seconds else 0.0
        block_times = _paced(functools.partial(_send, self._graph.signal), utterance.audio)
        self._heard.final.wait(120.0)
        # A partial run the closing utterance cancelled is counted when the engine has stopped.
        time.sleep(3 * DIAGNOSTICS_PERIOD)
        return self._heard.run(config, block_times, self._worker_seconds[-1] - before)


def _word_delays(run: Run, utterance: Utterance) -> Tuple[List[float], int]:
    """Each final word's delay to the first partial that shows it; how many none showed."""
    words = run.final.split()
    delays: List[float] = []
    missed = 0
    for index, word_end in enumerate(utterance.word_ends[: len(words)]):
        heard_at = run.block_times[min(len(run.block_times) - 1, -(-word_end // BLOCK) - 1)]
        shown = [at for at, text in run.partials if text.split()[: index + 1] == words[: index + 1]]
        if shown:
            delays.append(shown[0] - heard_at)
        else:
            missed += 1
    return delays, missed


def _engines(wanted: List[str], roscore: bool) -> Dict[str, Engine]:
    large = os.environ.get("SPEECH_EVENT_LARGE_MODEL")
    engines: Dict[str, Engine] = {
        "fake (tones)": Engine("tones", "fake"),
        "NeMo engine, tones transducer": Engine(
            "tones", "nemo", lambda work: build_tones_model(work / "transducer")
        ),
        "Whisper engine, tones model": Engine(
            "tones", "whisper", lambda work: build_whisper_tones_model(work / "whisper")
        ),
        "pocketsphinx language model": Engine("tts", "pocketsphinx"),
    }
    if large:
        engines["large conformer (119 M, random weights)"] = Engine("tts", "nemo", lambda _: Path(large))
    elif not roscore:
        stand_in = Engine("tones", "", stand_in=LargeConformerStandIn)
        engines[f"large conformer stand-in (RTF {LARGE_RTF})"] = stand_in
    return {name: engine for name, engine in engines.items() if not wanted or any(w in name for w in wanted)}


def _summary(off: List[Run], on: List[Run], utterance: Utterance) -> str:
    delays: List[float] = []
    missed = words = 0
    for run in on:
        run_delays, run_missed = _word_delays(run, utterance)
        delays += run_delays
        missed += run_missed
        words += len(run.final.split())
    shown = (
        f"word to partial median {1000 * statistics.median(delays):5.0f} ms, "
        f"max {1000 * max(delays):5.0f} ms, {missed} of {words} never shown"
        if delays
        else f"no word of the final text in a partial ({words} words)"
    )
    counts = [len(run.partials) for run in on]
    share = statistics.median(run.partial_seconds for run in on) / (utterance.audio.size / RATE)
    return (
        f"{statistics.median(counts):4.1f} partials ({min(counts)}-{max(counts)}); {shown}; worker "
        f"{100 * share:4.1f} %; final {_latencies(off)} without, {_latencies(on)} with"
    )


def _latencies(runs: List[Run]) -> str:
    latencies = [run.final_latency for run in runs]
    return f"{1000 * statistics.median(latencies):5.0f} ({1000 * max(latencies):5.0f} max) ms"


def main() -> None:
    parser = argparse.ArgumentParser(description="Partial results' figures (issue 20).")
    parser.add_argument("--roscore", action="store_true", help="the node as a process on a roscore")
    parser.add_argument("--runs", type=int, default=3, help="runs per figure, partials off and on")
    parser.add_argument("engines", nargs="*", help="only the engines whose names contain one of these")
    arguments = parser.parse_args()
    off = SpeechEventConfig(
        health_check_period=3600.0, max_utterance_length=30.0, partial_period=0.0, publish_unrecognized=True
    )
    on = dataclasses.replace(off, partial_period=0.5)
    with contextlib.ExitStack() as stack:
        work = Path(stack.enter_context(tempfile.TemporaryDirectory()))
        player: Callable[[Engine, SpeechEventConfig], ContextManager[Play]] = in_memory
        if arguments.roscore:
            from bench.figures.ros_graph import ros_graph  # rospy: only here

            player = OnRoscore(stack.enter_context(ros_graph("speech_event_bench_partial_")))
        where = "roscore" if arguments.roscore else "memory"
        for name, engine in _engines(arguments.engines, arguments.roscore).items():
            utterances = {seconds: _utterance(engine.voice, seconds) for seconds in LENGTHS}
            model = engine.model(work) if engine.model else None  # built once, for both configurations
            runs: Dict[Tuple[float, SpeechEventConfig], List[Run]] = {}
            for config in (off, on):
                with player(engine, engine.config(config, model)) as play:
                    for seconds, utterance in utterances.items():
                        runs[seconds, config] = [play(utterance) for _ in range(arguments.runs)]
            for seconds, utterance in utterances.items():
                summary = _summary(runs[seconds, off], runs[seconds, on], utterance)
                print(f"{where}: {name:34s} {seconds:4.0f} s: {summary}", flush=True)


if __name__ == "__main__":
    main()
