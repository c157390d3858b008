"""resample -> screen -> transcribe: one utterance's recognition, run on the worker (for a closed
utterance or a speculation). It never raises: a failure is part of the outcome, said when the
utterance is published (a cancelled speculation never is)."""

from typing import Callable, Optional

from speech_event.pipeline.recognition_queue import RecognitionOutcome
from speech_event.pipeline.resample import resample
from speech_event.pipeline.screen import SpeechScreen
from speech_event.ports import Audio, Recognizer


class Recognition:
    """Audio at the node's rate in, what the engine made of it out, timed with ``stopwatch``."""

    def __init__(self, sample_rate: int, screen: SpeechScreen, stopwatch: Callable[[], float]) -> None:
        self._sample_rate = sample_rate
        self._screen = screen
        self._stopwatch = stopwatch

    def __call__(self, audio: Audio, recognizer: Recognizer) -> RecognitionOutcome:
        """Resample for ``recognizer``, screen, transcribe."""
        began: Optional[float] = None
        try:
            speech = resample(audio, self._sample_rate, recognizer.sample_rate)
            discard = self._screen.discard(speech, recognizer.sample_rate)
            if discard is not None:
                return RecognitionOutcome(discard=discard)
            began = self._stopwatch()
            answer = recognizer.transcribe(speech)
            return RecognitionOutcome(answer, took=self._stopwatch() - began)
        # A failed recognition must not stop the node; SystemExit from an engine is a failure like
        # any other. Its time counts too: a speculation stopped mid-run wasted it.
        except (Exception, SystemExit) as problem:
            took = 0.0 if began is None else self._stopwatch() - began
            return RecognitionOutcome(error=problem, took=took)
