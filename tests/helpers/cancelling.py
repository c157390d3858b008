"""Stopping an engine's transcription from another thread, as the node's watchdog and speculation do."""

import threading
from typing import List

import numpy as np

from speech_event.ports import Recognizer, Stoppable


def failures_of_a_cancelled_transcription(engine: Recognizer, audio: np.ndarray) -> List[BaseException]:
    """What ``engine.transcribe(audio)`` raised when ``stop`` was called while it ran.

    ``stop`` is called again and again until the transcription ends: a call before it began
    stops nothing (there is no run yet), so no peeking at the engine's state is needed."""
    assert isinstance(engine, Stoppable)
    failures: List[BaseException] = []

    def transcribe() -> None:
        try:
            engine.transcribe(audio)
        except Exception as problem:  # onnxruntime's own exception type
            failures.append(problem)

    worker = threading.Thread(target=transcribe)
    worker.start()
    while worker.is_alive():
        engine.stop()
        worker.join(0.001)
    return failures
