"""Step 5 of the pipeline, after resampling: is this utterance speech worth transcribing?

The robot's release drops utterances shorter than ``minUtteranceLen`` and those whose Silero VAD
speech probability stays below ``vadThreshold``. Neither is speech the engine failed to read, so
the node publishes nothing for them, not even ``Error: speech not recognized``.
"""

import enum
from typing import Callable, Optional

import numpy as np

from speech_event.config import SpeechEventConfig
from speech_event.pipeline.assembly import NonSpeech
from speech_event.pipeline.resample import resample
from speech_event.pipeline.vad import SAMPLE_RATE as VAD_RATE
from speech_event.pipeline.vad import SileroVad, silero_model_path


class Discard(enum.Enum):
    """Why an utterance is not transcribed; the value names it in /diagnostics."""

    TOO_SHORT = "too_short"
    BELOW_VAD_THRESHOLD = "below_vad_threshold"


# 16 kHz audio -> its highest speech probability (SileroVad.max_speech_probability).
SpeechProbability = Callable[[np.ndarray], float]


class SpeechScreen:
    """Tells an utterance that is not speech: shorter than ``min_seconds``, or below the VAD threshold."""

    def __init__(
        self,
        min_seconds: float,
        vad_threshold: float,
        speech_probability: Optional[SpeechProbability],
        non_speech: Optional[NonSpeech] = None,
    ) -> None:
        assert vad_threshold <= 0 or speech_probability is not None, "a VAD threshold needs a VAD"
        self._min_seconds = min_seconds
        self._vad_threshold = vad_threshold
        self._speech_probability = speech_probability
        # Where the VAD hears no speech, for the length cut (speech_event/pipeline/assembly.py); None: energy.
        self.non_speech = non_speech

    def discard(self, audio: np.ndarray, sample_rate: int) -> Optional[Discard]:
        """Why ``audio`` is not transcribed, or None when it is speech to transcribe."""
        if audio.size / sample_rate < self._min_seconds:
            return Discard.TOO_SHORT
        if self._vad_threshold > 0 and self._speech_probability is not None:
            at_vad_rate = resample(audio, sample_rate, VAD_RATE)
            if self._speech_probability(at_vad_rate) < self._vad_threshold:
                return Discard.BELOW_VAD_THRESHOLD
        return None


def speech_screen_for(config: SpeechEventConfig) -> SpeechScreen:
    """The screen the configuration asks for; ModelError when the VAD it needs is not installed."""
    if config.vad_threshold <= 0:
        return SpeechScreen(config.min_utterance_length, 0.0, None)
    vad = SileroVad(silero_model_path())
    return SpeechScreen(
        config.min_utterance_length,
        config.vad_threshold,
        vad.max_speech_probability,
        vad.non_speech(config.vad_threshold),
    )
