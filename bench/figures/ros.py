"""Figures on a real roscore (python -m bench.figures.ros, in the tox env ros or a venv that sees rospy).

Targets, from the issue: last block of an utterance to its text at a subscriber, minus
speech_pause_period, at most 20 ms with the fake recognizer; blocks lost in a burst of 1000: 0.
Also the per-block cost including the conversion of the ROS message to numpy.
"""

import contextlib
import io
import statistics
import time
import xmlrpc.client
from typing import Any, Callable, List

import numpy as np
import rosgraph
import rospy
from rospy.numpy_msg import numpy_msg
from std_msgs import msg as std_msgs

from bench.figures import latency
from bench.figures.ros_graph import RosGraph, ros_graph
from fixtures.audio import noise, speak_tones
from harness.catalog import TRAINED_MODELS
from harness.processes import ReplayError, wait_until
from speech_event import SIGNAL_TOPIC, TEXT_TOPIC
from speech_event.adapters.executors import ClockExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.config import SpeechEventConfig
from speech_event.messages import Float32MultiArray, String
from speech_event.node import SpeechEventNode
from speech_event.recognizers.tones import ToneRecognizer

BLOCK = 4096
RATE = 48000


def per_block_cost(blocks: int = 5000) -> None:
    """Deserializing a 4096-float message and handling it, without the network."""
    buffer = io.BytesIO()
    samples = np.random.default_rng(0).uniform(-0.5, 0.5, BLOCK).astype(np.float32)
    std_msgs.Float32MultiArray(data=samples.tolist()).serialize(buffer)
    wire = buffer.getvalue()
    clock, bus = FakeClock(), InMemoryBus()
    node = SpeechEventNode(SpeechEventConfig(), bus, clock, ToneRecognizer(), ClockExecutor(clock))
    bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    node.start()
    deserializers = (
        ("numpy_msg", numpy_msg(std_msgs.Float32MultiArray)),
        ("plain", std_msgs.Float32MultiArray),
    )
    for label, message_class in deserializers:
        costs: List[float] = []
        for _ in range(blocks):
            clock.advance(BLOCK / RATE)
            start = time.perf_counter()
            node.on_signal(message_class().deserialize(wire))
            costs.append(time.perf_counter() - start)
        costs.sort()
        print(
            f"block with conversion ({label} deserializer): {statistics.mean(costs) * 1e3:.4f} ms mean, "
            f"{costs[int(len(costs) * 0.99)] * 1e3:.4f} ms p99 over {blocks} blocks"
        )


def _received(node_uri: str) -> int:
    stats: Any = xmlrpc.client.ServerProxy(node_uri).getBusStats("/bench")
    return sum(int(c[2]) for topic, connections in stats[2][1] if topic == SIGNAL_TOPIC for c in connections)


def on_roscore(utterances: int = 5, burst: int = 1000) -> None:
    with ros_graph("speech_event_bench_") as graph:
        config = SpeechEventConfig()
        arrivals: List[float] = []
        texts: List[str] = []

        def on_text(message: object) -> None:
            arrivals.append(time.perf_counter())
            texts.append(message.data)  # type: ignore[attr-defined]

        graph.transport.subscribe(TEXT_TOPIC, String, on_text)
        spoken = speak_tones("go to the kitchen", RATE)
        padded = np.zeros(-(-spoken.size // BLOCK) * BLOCK, dtype=np.float32)
        padded[: spoken.size] = spoken
        runs = (("without speculation", "speculative_recognition false\n"), ("with speculation", ""))
        for label, settings in runs:
            node = graph.start_node(settings, "fake", graph.subscribed(TEXT_TOPIC))
            latencies: List[float] = []
            texts.clear()
            for _ in range(utterances):
                count = len(texts)
                for block in padded.reshape(-1, BLOCK):
                    time.sleep(BLOCK / RATE)  # as soundDetection: a block when it has been recorded
                    graph.signal.publish(Float32MultiArray(data=block))
                    last_block = time.perf_counter()
                wait_until(_more_than(texts, count), "the text", 10)
                latencies.append(arrivals[-1] - last_block - config.speech_pause_period)
            assert texts == ["go to the kitchen"] * utterances, texts
            print(
                f"roscore: last block to text minus the {config.speech_pause_period} s pause, {label}: "
                f"{statistics.median(latencies) * 1e3:.1f} ms median, "
                f"{max(latencies) * 1e3:.1f} ms max over {utterances} utterances, fake recognizer "
                "(target <= 20 ms)"
            )
            if settings:  # the last node, with speculation (the default), stays for what follows
                graph.stop_node(node)
        node_uri = str(rosgraph.Master("/bench").lookupNode("/speechEvent"))

        service_round_trips()

        before = _received(node_uri)
        quiet = noise(BLOCK * burst, -40.0, np.random.default_rng(1)).reshape(burst, BLOCK)
        start = time.perf_counter()
        for block in quiet:
            graph.signal.publish(Float32MultiArray(data=block))
        sent = time.perf_counter() - start
        with contextlib.suppress(ReplayError):  # what did not arrive in 30 s is counted as lost
            wait_until(lambda: _received(node_uri) - before >= burst, "the burst", 30)
        received = _received(node_uri) - before
        print(
            f"roscore: burst of {burst} blocks published in {sent * 1e3:.0f} ms: "
            f"{received} received by the node, {burst - received} lost (target 0)"
        )
        graph.stop_node(node)
        engines_on_roscore(graph)


def service_round_trips(calls: int = 200) -> None:
    """set_enabled and set_language (the engine already built) as the Behaviour Controller calls them."""
    from speech_event.srv import SetEnabled, SetLanguage

    for name, kind, requests in (
        ("set_enabled", SetEnabled, ("false", "true")),
        ("set_language", SetLanguage, ("Kinyarwanda", "English")),
    ):
        rospy.wait_for_service(f"/speechEvent/{name}", timeout=30)
        call = rospy.ServiceProxy(f"/speechEvent/{name}", kind, persistent=False)
        times: List[float] = []
        for number in range(calls):
            start = time.perf_counter()
            assert call(requests[number % 2]).response == 1
            times.append(time.perf_counter() - start)
        print(
            f"roscore: {name} round trip {statistics.median(times) * 1e3:.2f} ms median, "
            f"{max(times) * 1e3:.2f} ms max ({calls} calls, a new connection each, as rosservice)"
        )


def engines_on_roscore(graph: RosGraph) -> None:
    """bench/figures/latency.py's figure (a) on a real roscore, 2 runs each, for its engines but the trained
    Whisper models (python -m bench.figures.latency --roscore whisper runs those)."""
    chosen = {
        name: engine for name, engine in latency.engines().items() if engine.recognizer not in TRAINED_MODELS
    }
    latency.roscore_latency(graph, chosen, runs=2)


def _more_than(texts: List[Any], count: int) -> Callable[[], bool]:
    return lambda: len(texts) > count


if __name__ == "__main__":
    per_block_cost()
    on_roscore()
