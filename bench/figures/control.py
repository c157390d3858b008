"""Runtime control figures (python -m bench.figures.control); the ROS round trips are in bench.figures.ros.

(a) time to answer set_enabled, and set_language when the engine is already built;
(b) the switch itself: set_language building the other language's NeMo engine (the tones fixture
    model, and a random transducer with a conformer-large-sized prediction network and joint);
(c) how long recognition is held up by a switch: the recognition worker's latency (utterance
    closed to text published) for back-to-back utterances, alone and while another thread
    builds an engine with set_language.
"""

import statistics
import tempfile
import threading
import time
from pathlib import Path
from typing import Callable, List, Tuple

import numpy as np

from fixtures.audio import speak_tones
from fixtures.tones_model import build_tones_model
from fixtures.transducer_model import build_random_transducer
from speech_event import SIGNAL_TOPIC, TEXT_TOPIC
from speech_event.adapters.executors import ClockExecutor, ThreadExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.config import SpeechEventConfig
from speech_event.interfaces.services import SET_ENABLED_SERVICE, SET_LANGUAGE_SERVICE
from speech_event.messages import Float32MultiArray, SetEnabledRequest, SetLanguageRequest, String
from speech_event.node import SpeechEventNode
from speech_event.ports import EngineBuilder, Executor, Recognizer
from speech_event.recognizers.nemo.recognizer import NemoRecognizer
from speech_event.recognizers.tones import ToneRecognizer

CONFIG = SpeechEventConfig(sample_rate=16000, health_check_period=3600.0)


def _node(
    recognizer: Recognizer, build: EngineBuilder, executor: Callable[[FakeClock], Executor]
) -> Tuple[FakeClock, InMemoryBus, SpeechEventNode]:
    clock, bus = FakeClock(), InMemoryBus()
    node = SpeechEventNode(CONFIG, bus, clock, recognizer, executor(clock), build)
    bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    node.start()
    return clock, bus, node


def _micros(samples: List[float]) -> str:
    return f"{statistics.median(samples) * 1e6:.1f} us median, {max(samples) * 1e6:.1f} us max"


def answer_times(calls: int = 2000) -> None:
    _, bus, _ = _node(ToneRecognizer(), lambda language: ToneRecognizer(), ClockExecutor)
    enabled: List[float] = []
    switched: List[float] = []
    for number in range(calls):
        start = time.perf_counter()
        bus.call(SET_ENABLED_SERVICE, SetEnabledRequest("false" if number % 2 else "true"))
        enabled.append(time.perf_counter() - start)
        start = time.perf_counter()
        bus.call(SET_LANGUAGE_SERVICE, SetLanguageRequest("Kinyarwanda" if number % 2 else "English"))
        switched.append(time.perf_counter() - start)
    print(f"set_enabled answered in {_micros(enabled)} ({calls} calls, in memory)")
    print(f"set_language, engine already built, answered in {_micros(switched)} ({calls} calls, in memory)")


def switch_with_build(name: str, directory: Path, runs: int = 5) -> None:
    times: List[float] = []
    for _ in range(runs):
        _, bus, node = _node(ToneRecognizer(), lambda language: NemoRecognizer(directory), ClockExecutor)
        start = time.perf_counter()
        answer = bus.call(SET_LANGUAGE_SERVICE, SetLanguageRequest("Kinyarwanda"))
        times.append(time.perf_counter() - start)
        assert answer.response == 1 and node.language == "kinyarwanda"  # type: ignore[attr-defined]
    print(
        f"set_language building the {name}: {statistics.median(times) * 1e3:.1f} ms median, "
        f"{max(times) * 1e3:.1f} ms max ({runs} switches)"
    )


def _worker_latencies(directory: Path, speech: np.ndarray, utterances: int, builds: int) -> List[float]:
    """Closed-to-published times of back-to-back utterances; with ``builds``, another thread switches
    language once (building the Kinyarwanda engine) and builds builds - 1 more engines meanwhile."""
    executor = ThreadExecutor()
    clock, bus, node = _node(
        NemoRecognizer(directory),
        lambda language: NemoRecognizer(directory),
        lambda _: executor,
    )
    closed: List[float] = []
    published: List[float] = []
    bus.subscribe(TEXT_TOPIC, String, lambda message: published.append(time.perf_counter()))

    def switch() -> None:
        bus.call(SET_LANGUAGE_SERVICE, SetLanguageRequest("Kinyarwanda"))
        for _ in range(builds - 1):
            NemoRecognizer(directory)

    switcher = threading.Thread(target=switch)
    if builds:
        switcher.start()
    for _ in range(utterances):
        node.on_signal(Float32MultiArray(data=speech))
        clock.advance(CONFIG.speech_pause_period + 0.01)
        closed.append(time.perf_counter())
        while len(published) < len(closed):
            time.sleep(0.0005)
    if builds:
        switcher.join()
    executor.shutdown(10)
    return [done - start for start, done in zip(closed, published)]


def held_up(directory: Path, utterances: int = 30, builds: int = 6) -> None:
    """Latency of the recognition worker, alone and while set_language builds engines meanwhile."""
    speech = speak_tones("go to the kitchen and bring me the red cup", 16000)
    for label, count in (("alone", 0), (f"during {builds} engine builds", builds)):
        latency = _worker_latencies(directory, speech, utterances, count)
        print(
            f"recognition worker {label}: closed to published {statistics.median(latency) * 1e3:.1f} ms "
            f"median, {max(latency) * 1e3:.1f} ms max "
            f"({utterances} utterances of {speech.size / 16000:.1f} s)"
        )


if __name__ == "__main__":
    answer_times()
    with tempfile.TemporaryDirectory() as work:
        tones = build_tones_model(Path(work) / "tones")
        large = build_random_transducer(Path(work) / "large", width=512, hidden=640, joint=640)
        size = sum(path.stat().st_size for path in large.glob("*.onnx")) / 1e6
        switch_with_build("tones fixture model", tones)
        switch_with_build(f"random transducer ({size:.1f} MB of ONNX)", large)
        held_up(large)
