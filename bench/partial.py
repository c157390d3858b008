"""Partial results (python -m bench.partial [ENGINE ...]), issue 20: in memory, in real time.

The node runs on the wall clock with its thread executor; soundDetection's blocks (4096 samples at
48 kHz) are published at the pace they are recorded, 85 ms apart. For each engine and an utterance
of 3 and of 10 s:

- words: for each word of the final text, the delay from the block its sound ends in to the first
  partial whose words begin with the final's words up to it (median and max), and how many of the
  final's words no partial ever showed;
- partials: how many came for the utterance;
- worker: the engine time the partial runs and feeds took, as a share of the utterance's length;
- final: last block to the final text, minus the pause, with partials off and on (the target: no
  measurable difference, as closed utterances come first and a closing utterance cancels a run).

Word ends: the tones voice is concatenative (a word ends where the text up to it, spoken alone,
ends, less its trailing gap); espeak's (tts) is taken the same way, an approximation.
Engines: the fake (tones), the NeMo engine on the tones transducer, the Whisper engine on the tones
Whisper model, pocketsphinx with its language model (tts), and the large conformer as in
bench/latency.py (SPEECH_EVENT_LARGE_MODEL=DIR, or its stand-in that answers nothing).
"""

import dataclasses
import statistics
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Dict, List, Tuple

import numpy as np

from bench.latency import _large_conformer
from fixtures.audio import normalise_text, speak_tones
from fixtures.tones_model import build_tones_model
from fixtures.tts import speak_tts
from fixtures.whisper_tones_model import build_whisper_tones_model
from speech_event import PARTIAL_TOPIC, SIGNAL_TOPIC, TEXT_TOPIC
from speech_event.adapters.executors import ThreadExecutor
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.adapters.system_clock import SystemClock
from speech_event.config import SpeechEventConfig
from speech_event.messages import Float32MultiArray, String
from speech_event.node import SpeechEventNode
from speech_event.ports import Recognizer
from speech_event.recognizers.nemo.recognizer import NemoRecognizer
from speech_event.recognizers.sphinx import SphinxRecognizer
from speech_event.recognizers.tones import ToneRecognizer
from speech_event.recognizers.whisper.recognizer import WhisperRecognizer

RATE = 48000
BLOCK = 4096
LENGTHS = (3.0, 10.0)
SENTENCE = "please go to the kitchen and bring me a glass of water then come back to the door"
Speak = Callable[[str, int], np.ndarray]
VOICES: Dict[str, Speak] = {"tones": speak_tones, "tts": speak_tts}
WORD_GAP = int(0.09 * RATE)  # the tones voice's trailing gap (fixtures/audio.py)


@dataclass(frozen=True)
class Utterance:
    audio: np.ndarray
    word_ends: List[int]  # the sample each word's sound ends at


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


def _run(recognizer: Recognizer, config: SpeechEventConfig, utterance: Utterance) -> Run:
    clock, bus, executor = SystemClock(), InMemoryBus(), ThreadExecutor()
    finished = threading.Event()
    finals: List[Tuple[float, str]] = []
    partials: List[Tuple[float, str]] = []

    def on_text(message: object) -> None:
        finals.append((time.monotonic(), message.data))  # type: ignore[attr-defined]
        finished.set()

    bus.subscribe(TEXT_TOPIC, String, on_text)
    bus.subscribe(PARTIAL_TOPIC, String, lambda m: partials.append((time.monotonic(), m.data)))  # type: ignore[attr-defined]
    node = SpeechEventNode(
        dataclasses.replace(config, publish_unrecognized=True), bus, clock, recognizer, executor
    )
    sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    node.start()
    block_times: List[float] = []
    began = time.monotonic()
    for number, start in enumerate(range(0, utterance.audio.size, BLOCK)):
        time.sleep(max(0.0, began + (number + 1) * BLOCK / RATE - time.monotonic()))
        sound_detection.publish(Float32MultiArray(data=utterance.audio[start : start + BLOCK]))
        block_times.append(time.monotonic())
    finished.wait(120.0)
    node.stop()
    executor.shutdown(120.0)
    latency = finals[0][0] - block_times[-1] - config.speech_pause_period
    return Run(latency, finals[0][1], partials, block_times, node.partials.worker_seconds)


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


def _engines(work: Path) -> Dict[str, Tuple[Callable[[], Recognizer], str]]:
    engines: Dict[str, Tuple[Callable[[], Recognizer], str]] = {
        "fake (tones)": (ToneRecognizer, "tones"),
        "NeMo engine, tones transducer": (lambda: NemoRecognizer(build_tones_model(work / "tones")), "tones"),
        "Whisper engine, tones model": (
            lambda: WhisperRecognizer(build_whisper_tones_model(work / "whisper"), "english"),
            "tones",
        ),
        "pocketsphinx language model": (SphinxRecognizer, "tts"),
        **_large_conformer(),
    }
    wanted = sys.argv[1:]
    return {name: engine for name, engine in engines.items() if not wanted or any(w in name for w in wanted)}


def main() -> None:
    off = SpeechEventConfig(health_check_period=3600.0, max_utterance_length=30.0, partial_period=0.0)
    on = dataclasses.replace(off, partial_period=0.5)
    with tempfile.TemporaryDirectory() as work:
        for name, (make, voice) in _engines(Path(work)).items():
            recognizer = make()
            for seconds in LENGTHS:
                utterance = _utterance(voice, seconds)
                without = _run(recognizer, off, utterance)
                run = _run(recognizer, on, utterance)
                delays, missed = _word_delays(run, utterance)
                words = (
                    f"word to partial median {1000 * statistics.median(delays):5.0f} ms, max "
                    f"{1000 * max(delays):5.0f} ms, {missed} of {len(run.final.split())} never shown"
                    if delays
                    else f"no word of the final text in a partial ({len(run.final.split())} words)"
                )
                share = run.partial_seconds / (utterance.audio.size / RATE)
                print(
                    f"{name:34s} {seconds:4.0f} s: {len(run.partials):2d} partials; {words}; worker "
                    f"{100 * share:4.1f} %; final {1000 * without.final_latency:5.0f} ms without, "
                    f"{1000 * run.final_latency:5.0f} ms with",
                    flush=True,
                )


if __name__ == "__main__":
    main()
