"""Figures for the hermetic core (python -m bench.figures.core). Targets, from the issue:
scenario replay >= 200x real time; one 4096-sample block <= 0.2 ms; utterance end to publish,
recognition excluded, <= 2 ms in memory."""

import logging
import statistics
import time
from pathlib import Path
from typing import List

import numpy as np

from harness.memory_runner import run_in_memory
from harness.scenario import load_scenario
from harness.timeline import build_timeline
from speech_event import SIGNAL_TOPIC, TEXT_TOPIC
from speech_event.adapters.executors import ClockExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.config import SpeechEventConfig
from speech_event.messages import Float32MultiArray, String
from speech_event.node import SpeechEventNode
from speech_event.ports import Transcript

ROOT = Path(__file__).resolve().parents[2]
BLOCK = 4096


class InstantRecognizer:
    """Costs nothing, so what is measured is the node's own work."""

    sample_rate = 16000

    def transcribe(self, audio: np.ndarray) -> Transcript:
        return Transcript("x")


def replay_speed() -> None:
    paths = sorted((ROOT / "scenarios").glob("*.toml"))
    scenarios = [load_scenario(path, SpeechEventConfig()) for path in paths]
    hermetic = [scenario for scenario in scenarios if scenario.recognizer == "fake"]
    for label, chosen in (
        ("hermetic (tones voice, fake recognizer)", hermetic),
        ("all, real engines included", scenarios),
    ):
        scenario_seconds = sum(build_timeline(scenario).end for scenario in chosen)
        start = time.perf_counter()
        for scenario in chosen:
            run_in_memory(scenario)
        wall = time.perf_counter() - start
        print(
            f"replay, {label}: {len(chosen)} scenarios, {scenario_seconds:.1f} s of scenario time in "
            f"{wall:.3f} s wall = {scenario_seconds / wall:.0f}x real time (target >= 200x)"
        )


def _node(config: SpeechEventConfig) -> "tuple[FakeClock, InMemoryBus, SpeechEventNode]":
    clock, bus = FakeClock(), InMemoryBus()
    node = SpeechEventNode(config, bus, clock, InstantRecognizer(), ClockExecutor(clock))
    bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    node.start()
    return clock, bus, node


def block_cost(blocks: int = 20000) -> None:
    # Long utterances so the length cut is part of the figure (once per 10 s of audio).
    clock, _, node = _node(SpeechEventConfig())
    rng = np.random.default_rng(0)
    messages = [Float32MultiArray(data=rng.uniform(-0.5, 0.5, BLOCK).astype(np.float32)) for _ in range(64)]
    costs: List[float] = []
    for index in range(blocks):
        clock.advance(BLOCK / 48000)
        start = time.perf_counter()
        node.on_signal(messages[index % len(messages)])
        costs.append(time.perf_counter() - start)
    costs.sort()
    print(
        f"block: one 4096-sample block costs {statistics.mean(costs) * 1e3:.4f} ms mean, "
        f"{costs[len(costs) // 2] * 1e3:.4f} ms median, {costs[int(len(costs) * 0.99)] * 1e3:.4f} ms p99 "
        f"over {blocks} blocks (target <= 0.2 ms)"
    )


class _PublishTimes:
    def __init__(self) -> None:
        self.times: List[float] = []

    def record(self, _message: object) -> None:
        self.times.append(time.perf_counter())


def end_to_publish(seconds: float, runs: int = 50) -> None:
    config = SpeechEventConfig(max_utterance_length=30.0, health_check_period=3600.0)
    rng = np.random.default_rng(1)
    audio = rng.uniform(-0.5, 0.5, int(seconds * 48000)).astype(np.float32)
    delays: List[float] = []
    for _ in range(runs):
        clock, bus, _ = _node(config)
        stamps = _PublishTimes()
        bus.subscribe(TEXT_TOPIC, String, stamps.record)
        sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
        for offset in range(0, audio.size, BLOCK):
            sound_detection.publish(Float32MultiArray(data=audio[offset : offset + BLOCK]))
        clock.advance(config.speech_pause_period - 1e-3)
        start = time.perf_counter()
        clock.advance(2e-3)  # the pause ends: close, resample, recognize (free), publish
        delays.append(stamps.times[0] - start)
    delays.sort()
    print(
        f"end to publish: {seconds:.0f} s utterance, {statistics.median(delays) * 1e3:.3f} ms median, "
        f"{delays[-1] * 1e3:.3f} ms max over {runs} runs, recognition excluded (target <= 2 ms)"
    )


if __name__ == "__main__":
    logging.getLogger("speech_event").setLevel(logging.ERROR)  # the scenarios' warnings are expected
    replay_speed()
    block_cost()
    for seconds in (1.0, 3.0, 10.0):
        end_to_publish(seconds)
