"""Hostile input and overload figures (python -m bench.figures.robustness).

(a) fuzz: 10,000 hostile messages (no audio, by construction) between the blocks of 100 spoken
    utterances, on the in-memory bus: exceptions out of the callback, wrong texts, samples lost
    (accepted speech that reached no recognition), and the memory peak (tracemalloc);
(b) overload: recognition 3x slower than speech for 10 minutes of speech (3 s utterances at
    48 kHz, each recognized in 9 s of clock): seconds of speech queued and the memory the queue
    holds, minute by minute, with max_backlog at its default of 120 s.
"""

import logging
import tracemalloc
from types import SimpleNamespace
from typing import Callable, List

import numpy as np

from fixtures.audio import speak_tones
from speech_event import SIGNAL_TOPIC, TEXT_TOPIC
from speech_event.adapters.executors import ClockExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.config import SpeechEventConfig
from speech_event.messages import Float32MultiArray, MultiArrayDimension, MultiArrayLayout, String
from speech_event.node import SpeechEventNode
from speech_event.ports import Transcript
from speech_event.recognizers.tones import ToneRecognizer

RATE = 48000
BLOCK = 4096


def _hostile_makers(rng: np.random.Generator) -> List[Callable[[], object]]:
    """Each makes one message that is no usable audio."""

    def audio(n: int = 8) -> np.ndarray:
        return rng.uniform(-1, 1, n).astype(np.float32)

    def as_message(data: object) -> object:
        return Float32MultiArray(data=data)  # type: ignore[arg-type]

    return [
        lambda: None,
        lambda: int(rng.integers(-(10**9), 10**9)),
        lambda: "text " * int(rng.integers(1, 5)),
        lambda: rng.bytes(16),
        lambda: {"data": audio().tolist()},
        lambda: String("not audio"),
        lambda: as_message(audio(64).reshape(8, 8)),
        lambda: as_message(np.float32(0.5)),
        lambda: as_message([[0.1, 0.2], [0.3]]),
        lambda: as_message([[0.1, 0.2], [0.3, 0.4]]),
        lambda: as_message("0.1 0.2"),
        lambda: as_message(b"\x00\x01"),
        lambda: as_message(None),
        lambda: as_message(x for x in (0.1, 0.2)),
        lambda: as_message(np.array([0.1, None], dtype=object)),
        lambda: as_message([*audio().tolist(), float("nan")]),
        lambda: as_message([*audio().tolist(), 1e300]),
        lambda: as_message(np.round(audio(BLOCK) * 32767)),
        lambda: as_message(np.zeros(0, np.float32)),
        lambda: Float32MultiArray(
            data=audio(2 * BLOCK),
            layout=MultiArrayLayout(dim=(MultiArrayDimension("c", 2, 2), MultiArrayDimension("s", BLOCK, 1))),
        ),
        lambda: SimpleNamespace(_type="std_msgs/Float32MultiArray", data=audio().tolist()),
        lambda: SimpleNamespace(
            _type="std_msgs/Float32MultiArray", layout=SimpleNamespace(dim=None), data=[0.1]
        ),
        lambda: SimpleNamespace(_type="std_msgs/Float32MultiArray", layout=SimpleNamespace(dim=[])),
    ]


class _Counting(ToneRecognizer):
    def __init__(self) -> None:
        self.samples = 0

    def transcribe(self, audio: np.ndarray) -> Transcript:
        self.samples += audio.size
        return super().transcribe(audio)


def fuzz(utterances: int = 100, per_utterance: int = 100) -> None:
    rng = np.random.default_rng(0)
    makers = _hostile_makers(rng)
    config = SpeechEventConfig(sample_rate=RATE, health_check_period=3600.0, max_message_length=1.0)
    clock, bus, recognizer = FakeClock(), InMemoryBus(), _Counting()
    node = SpeechEventNode(config, bus, clock, recognizer, ClockExecutor(clock))
    texts: List[str] = []
    bus.subscribe(TEXT_TOPIC, String, lambda message: texts.append(message.data))  # type: ignore[attr-defined]
    sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    node.start()
    phrase = "go to the kitchen"
    speech = speak_tones(phrase, RATE)
    padded = np.zeros(-(-speech.size // BLOCK) * BLOCK, dtype=np.float32)
    padded[: speech.size] = speech
    blocks = list(padded.reshape(-1, BLOCK))
    crashes = 0
    tracemalloc.start()
    for _ in range(utterances):
        hostile = [makers[int(rng.integers(len(makers)))]() for _ in range(per_utterance)]
        slots = np.sort(rng.integers(0, len(blocks) + 1, per_utterance))
        messages: List[object] = []
        for index, block in enumerate(blocks):
            messages += [hostile[i] for i in np.flatnonzero(slots == index)]
            messages.append(Float32MultiArray(data=block.copy()))
        messages += [hostile[i] for i in np.flatnonzero(slots == len(blocks))]
        for message in messages:
            clock.advance(BLOCK / RATE / 4)
            try:
                sound_detection.publish(message)
            except Exception:
                crashes += 1
        clock.advance(2.0)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    wrong = sum(1 for text in texts if text != phrase) + (utterances - len(texts))
    lost = utterances * padded.size * 16000 // RATE - recognizer.samples
    rejected = sum(node.rejection_counts.values())
    print(
        f"fuzz: {utterances * per_utterance} hostile messages between {utterances} utterances: "
        f"{crashes} exceptions out of the callback, {wrong} wrong or missing texts, "
        f"{lost} samples lost (at 16 kHz), {rejected} rejected, memory peak {peak / 1e6:.1f} MB"
    )


def overload(minutes: int = 10, slowdown: float = 3.0) -> None:
    speech_seconds, pause = 3.0, 1.5
    config = SpeechEventConfig(sample_rate=RATE, health_check_period=3600.0)
    clock, bus = FakeClock(), InMemoryBus()
    executor = ClockExecutor(clock, job_seconds=slowdown * speech_seconds)
    node = SpeechEventNode(config, bus, clock, ToneRecognizer(), executor)
    bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    node.start()
    utterance = np.full(int(speech_seconds * RATE), 0.1, dtype=np.float32)
    per_minute = int(60 / (speech_seconds + pause))
    print(f"overload: recognition {slowdown:.0f}x slower than speech, {speech_seconds:.0f} s utterances:")
    for minute in range(1, minutes + 1):
        for _ in range(per_minute):
            for start in range(0, utterance.size, BLOCK):
                clock.advance(BLOCK / RATE)
                node.on_signal(Float32MultiArray(data=utterance[start : start + BLOCK]))
            clock.advance(pause)
        queued = node.queued_speech_seconds
        print(
            f"  minute {minute:2d}: {queued:6.1f} s of speech queued ({queued * RATE * 4 / 1e6:5.1f} MB of "
            f"48 kHz float32), {node.dropped_utterances} utterances dropped so far"
        )


if __name__ == "__main__":
    # The node logs every rejection and drop (rate-limited); here only the figures matter.
    logging.getLogger("speech_event").setLevel(logging.CRITICAL)
    fuzz()
    overload()
