"""The sentences every parity check speaks, and the audio they are compared on.

Not the robot's commands (harness/data/robot_commands.txt): a fixed ten, some of them commands with
more words, that also train the random NeMo models' small tokenizer (random_nemo.py), so that a
parity figure stays comparable with those recorded before."""

from typing import List

import numpy as np

from fixtures.tts import speak_tts

PARITY_SENTENCES = [
    "go to the kitchen",
    "turn left",
    "stop",
    "bring me the red cup",
    "hello pepper",
    "what time is it",
    "open the door",
    "thank you very much",
    "follow me please",
    "good morning",
]


def parity_audio() -> List[np.ndarray]:
    """PARITY_SENTENCES spoken by espeak at 16 kHz, as a 16-bit recording would give them back: both
    runtimes are fed the same samples, which a robot's microphone could have sent."""
    return [_as_16_bit(speak_tts(sentence, 16000)) for sentence in PARITY_SENTENCES]


def _as_16_bit(audio: np.ndarray) -> np.ndarray:
    pcm: np.ndarray = np.round(np.clip(audio, -1, 1) * 32767).astype(np.int16)
    return pcm.astype(np.float32) / 32768.0
