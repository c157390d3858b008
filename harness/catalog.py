"""The voices that speak a scenario's text and the recognizers that can transcribe it, by name."""

import dataclasses
import re
from dataclasses import dataclass
from typing import Callable, Dict, Optional, Tuple

import numpy as np

from fixtures.audio import speak_tones
from fixtures.tts import speak_tts
from speech_event.config import SpeechEventConfig
from speech_event.ports import Recognizer
from speech_event.recognizers import RECOGNIZERS as ENGINES


@dataclass(frozen=True)
class Voice:
    # Turns text into mono float32 audio at the given sample rate.
    speak: Callable[[str, int], np.ndarray]
    # The characters it can speak, as a regular-expression class; None for any text.
    alphabet: Optional[str] = None

    def problem_with(self, text: str) -> Optional[str]:
        """Why this voice cannot speak ``text``, or None."""
        if self.alphabet is None:
            return None
        bad = sorted(set(re.sub(self.alphabet, "", text)))
        if bad:
            return "cannot speak {}; it speaks only {}".format(
                ", ".join(repr(character) for character in bad), self.alphabet
            )
        return None


VOICES: Dict[str, Voice] = {
    "tones": Voice(speak_tones, "[a-z' ]"),
    "tts": Voice(speak_tts, "[A-Za-z0-9',.?! -]"),
}

FIXTURE_MODEL = "fixture-model"
# The node's engines, plus the tones transducer built at test time (fixtures/tones_model.py).
RECOGNIZERS = (*ENGINES, FIXTURE_MODEL)


def engine_for(name: str, config: SpeechEventConfig) -> Tuple[str, SpeechEventConfig]:
    """The node's engine name and configuration for a scenario's recognizer.

    The fixture model is a real model directory: the node loads it as its English NeMo model, in
    memory and on ROS alike.
    """
    if name != FIXTURE_MODEL:
        return name, config
    from fixtures.tones_model import tones_model_directory

    return "nemo", dataclasses.replace(config, language="english", en_model_path=str(tones_model_directory()))


def recognizer_for(name: str, config: SpeechEventConfig) -> Recognizer:
    engine, engine_config = engine_for(name, config)
    return ENGINES[engine](engine_config)
