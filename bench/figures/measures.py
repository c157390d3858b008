"""What the engine figures share (asr.py, int8.py, sphinx_process.py and whisper_runtime.py beside
it): the robot commands they speak, word errors against a reference, this process's memory, and how
long an engine keeps the other threads from running."""

import threading
import time
from pathlib import Path
from typing import List, Tuple

import numpy as np

from fixtures.recordings import word_errors as recorded_word_errors
from speech_event.ports import Recognizer

COMMANDS = [
    "hello pepper",
    "goodbye",
    "thank you",
    "yes",
    "no",
    "stop",
    "follow me",
    "come here",
    "turn left",
    "turn right",
    "go forward",
    "go back",
    "go to the kitchen",
    "go to the living room",
    "go to the door",
    "open the door",
    "close the door",
    "bring me the red cup",
    "bring me the blue cup",
    "put it on the table",
    "pick up the ball",
    "what time is it",
    "what is your name",
    "how are you",
    "tell me a story",
    "play some music",
    "turn on the light",
    "turn off the light",
    "sit down",
    "stand up",
    "look at me",
    "wave your hand",
]


def word_errors(reference: str, hypothesis: str) -> Tuple[int, int]:
    """(word edits, reference words) between two texts' words as they are written."""
    return recorded_word_errors(reference.split(), hypothesis.split())


def peak_mib() -> float:
    """This process's peak resident memory: VmHWM, which starts afresh at exec (ru_maxrss does not:
    it would carry the parent's peak, the quantizer's among it)."""
    return _status_mib("VmHWM")


def resident_mib() -> float:
    """This process's resident memory now (VmRSS)."""
    return _status_mib("VmRSS")


def _status_mib(field: str) -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(f"{field}:"):
            return int(line.split()[1]) / 1024
    raise RuntimeError(f"no {field} in /proc/self/status")


def longest_stall(engine: Recognizer, audio: np.ndarray) -> float:
    """The longest a thread waking every 5 ms waited for its turn while ``engine`` transcribed
    ``audio``: how long the engine kept the node's other threads (timers, callbacks) from running."""
    ticks: List[float] = []
    done = threading.Event()

    def tick() -> None:
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.005)

    ticker = threading.Thread(target=tick)
    ticker.start()
    time.sleep(0.05)
    began = time.perf_counter()
    engine.transcribe(audio)
    ended = time.perf_counter()
    time.sleep(0.05)
    done.set()
    ticker.join()
    return max(
        later - earlier for earlier, later in zip(ticks, ticks[1:]) if later > began and earlier < ended
    )
