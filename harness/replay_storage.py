"""``python -m harness replay-storage DIR``: stored field recordings through the node, again.

Each utterance in DIR's index (``audio_storage_dir``, speech_event/pipeline/storage.py) is played to the
node on the in-memory bus in its language, and what the node publishes now is compared with what
it published then: regression testing from field recordings. Recordings the size bound removed
are listed as gone, not counted as changed.
"""

import dataclasses
from pathlib import Path
from typing import Dict, List

import numpy as np

from harness.catalog import ScenarioEngines
from harness.driver import read_audio
from harness.scenario import ScenarioError
from speech_event import SIGNAL_TOPIC, TEXT_TOPIC
from speech_event.adapters.executors import ClockExecutor
from speech_event.adapters.fake_clock import FakeClock
from speech_event.adapters.memory_bus import InMemoryBus
from speech_event.config import SpeechEventConfig
from speech_event.messages import Float32MultiArray, String
from speech_event.node import SpeechEventNode
from speech_event.pipeline.storage import INDEX_NAME, STORED_RATE, read_index
from speech_event.ports import Recognizer

BLOCK = 4096  # soundDetection's block


def published_for(audio: np.ndarray, config: SpeechEventConfig, recognizer: Recognizer) -> List[str]:
    """What the node publishes for ``audio`` said once, at ``config.sample_rate``, then silence."""
    clock, bus = FakeClock(), InMemoryBus()
    texts: List[str] = []
    bus.subscribe(TEXT_TOPIC, String, lambda message: texts.append(message.data))  # type: ignore[attr-defined]
    node = SpeechEventNode(config, bus, clock, recognizer, ClockExecutor(clock))
    sound_detection = bus.advertise(SIGNAL_TOPIC, Float32MultiArray, node="soundDetection")
    node.start()
    for start in range(0, audio.size, BLOCK):
        clock.advance(BLOCK / config.sample_rate)
        sound_detection.publish(Float32MultiArray(data=audio[start : start + BLOCK]))
    clock.advance(config.speech_pause_period + 0.1)
    node.stop()
    return texts


def replay_storage(directory: str, recognizer_name: str, base: SpeechEventConfig) -> int:
    folder = Path(directory)
    if not (folder / INDEX_NAME).is_file():
        raise ScenarioError(f"{directory}: no {INDEX_NAME}; give a folder the node stored utterances in")
    # The stored rate, no storing, and health checks that never publish an error in between.
    config = dataclasses.replace(
        base, sample_rate=STORED_RATE, audio_storage_dir="", health_check_period=3600.0
    )
    recognizers: Dict[str, Recognizer] = {}
    counts = {"same": 0, "changed": 0, "gone": 0}
    with ScenarioEngines(recognizer_name, config) as engines:
        for line in read_index(folder):
            if not (folder / line.file).is_file():
                counts["gone"] += 1
                print(f"gone     {line.file}  (removed to keep the folder under audio_storage_max_mb)")
                continue
            if line.language not in recognizers:
                recognizers[line.language] = engines.build(line.language)
            audio = read_audio(folder / line.file, STORED_RATE)
            language_config = dataclasses.replace(config, language=line.language)
            now = published_for(audio, language_config, recognizers[line.language])
            then = [line.published] if line.published is not None else []
            verdict = "same" if now == then else "changed"
            counts[verdict] += 1
            print(f"{verdict:<8} {line.file}  {_said(then)}" + ("" if now == then else f" -> {_said(now)}"))
    print(f"{counts['same']} same, {counts['changed']} changed, {counts['gone']} gone")
    return 1 if counts["changed"] else 0


def _said(texts: List[str]) -> str:
    return " | ".join(repr(text) for text in texts) if texts else "(nothing published)"
