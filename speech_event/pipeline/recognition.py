"""Step 6 of the pipeline, resample -> screen -> transcribe: one utterance's recognition, run on
the worker (for a closed utterance or a speculation). It never raises: a failure is part of the
outcome, said when the utterance is published (a cancelled speculation never is).

The grammar goes to the engine here, on the worker, just before it transcribes: an utterance
closed before a set_grammar is recognized with the grammar in force when it closed."""

from typing import Callable, Optional

from speech_event.grammar import Grammar
from speech_event.pipeline.recognition_queue import RecognitionOutcome
from speech_event.pipeline.resample import resample
from speech_event.pipeline.screen import SpeechScreen
from speech_event.ports import Audio, Grammars, Recognizer

# One utterance's audio recognized with an engine and a grammar (a Recognition, or a test's stand-in).
Recognize = Callable[[Audio, Recognizer, Optional[Grammar]], RecognitionOutcome]


class Recognition:
    """Audio at the node's rate in, what the engine made of it out, timed with ``stopwatch``."""

    def __init__(self, sample_rate: int, screen: SpeechScreen, stopwatch: Callable[[], float]) -> None:
        self._sample_rate = sample_rate
        self._screen = screen
        self._stopwatch = stopwatch

    def __call__(
        self, audio: Audio, recognizer: Recognizer, grammar: Optional[Grammar] = None
    ) -> RecognitionOutcome:
        """Resample for ``recognizer``, screen, transcribe within ``grammar`` (None: free speech)."""
        began: Optional[float] = None
        try:
            speech = resample(audio, self._sample_rate, recognizer.sample_rate)
            discard = self._screen.discard(speech, recognizer.sample_rate)
            if discard is not None:
                return RecognitionOutcome(discard=discard)
            began = self._stopwatch()
            if isinstance(recognizer, Grammars):  # the node never gives a grammar to another engine
                recognizer.use_grammar(grammar)
            answer = recognizer.transcribe(speech)
            return RecognitionOutcome(answer, took=self._stopwatch() - began)
        # A failed recognition must not stop the node; SystemExit from an engine is a failure like
        # any other. Its time counts too: a speculation stopped mid-run wasted it.
        except (Exception, SystemExit) as problem:
            took = 0.0 if began is None else self._stopwatch() - began
            return RecognitionOutcome(error=problem, took=took)
