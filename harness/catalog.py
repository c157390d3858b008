"""The voices that speak a scenario's text and the recognizers that can transcribe it, by name."""

import re
from dataclasses import dataclass
from typing import Callable, Dict, Optional

import numpy as np

from fixtures.audio import speak_tones
from fixtures.tts import speak_tts
from speech_event.recognizers import RECOGNIZERS


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

__all__ = ["RECOGNIZERS", "VOICES", "Voice"]
