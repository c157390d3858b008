"""Test doubles for the Recognizer port."""

import threading
from typing import List

import numpy as np

from speech_event.ports import Transcript

HEARD = Transcript("heard")


class SpyRecognizer:
    """Records every utterance it is given; answers with a fixed transcript."""

    sample_rate = 16000

    def __init__(self, answer: Transcript = HEARD) -> None:
        self.answer = answer
        self.utterances: List[np.ndarray] = []

    def transcribe(self, audio: np.ndarray) -> Transcript:
        self.utterances.append(audio.copy())
        return self.answer


class StoppableRecognizer(SpyRecognizer):
    """An engine that can be stopped; counts the stops."""

    def __init__(self) -> None:
        super().__init__()
        self.stops = 0

    def stop(self) -> None:
        self.stops += 1


class GatedRecognizer(SpyRecognizer):
    """Blocks in transcribe until the test opens the gate: a recognition that takes long."""

    def __init__(self) -> None:
        super().__init__()
        self.started = threading.Event()
        self.gate = threading.Event()

    def transcribe(self, audio: np.ndarray) -> Transcript:
        self.started.set()
        if not self.gate.wait(timeout=30):
            raise TimeoutError("the test never opened the gate")
        return super().transcribe(audio)


class FailingRecognizer(SpyRecognizer):
    """Fails on its first utterance, then works."""

    def transcribe(self, audio: np.ndarray) -> Transcript:
        if not self.utterances:
            self.utterances.append(audio.copy())
            raise RuntimeError("engine fell over")
        return super().transcribe(audio)
