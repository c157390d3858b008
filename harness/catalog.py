"""The voices that speak a scenario's text and the recognizers that can transcribe it, by name."""

import dataclasses
import re
from dataclasses import dataclass
from typing import Any, Callable, Dict, Optional, Tuple

import numpy as np

from fixtures.audio import speak_tones
from fixtures.tts import speak_tts
from speech_event.config import PATH_KEYS, SpeechEventConfig
from speech_event.engines import EngineBuilder
from speech_event.ports import Recognizer
from speech_event.recognizers import RECOGNIZERS as ENGINES
from speech_event.recognizers import engine_builder


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
FIXTURE_PARAKEET = "fixture-parakeet"
FIXTURE_WHISPER = "fixture-whisper"
# The node's engines, plus the tones models built at test time: the conformer-transducer's RNN-T
# and the parakeet family's TDT format (fixtures/tones_model.py), and a Whisper model
# (fixtures/whisper_tones_model.py).
RECOGNIZERS = (*ENGINES, FIXTURE_MODEL, FIXTURE_PARAKEET, FIXTURE_WHISPER)
# A model path written so in a scenario's [config] is a model built at test time.
FIXTURE_PREFIX = "fixture:"
FIXTURE_TONES = "fixture:tones"


def _tones_model() -> str:
    from fixtures.tones_model import tones_model_directory

    return str(tones_model_directory())


def _tones_tdt_model() -> str:
    from fixtures.tones_model import tones_tdt_model_directory

    return str(tones_tdt_model_directory())


def _whisper_tones_model() -> str:
    from fixtures.whisper_tones_model import whisper_tones_model_directory

    return str(whisper_tones_model_directory())


def _fixture_paths(config: SpeechEventConfig) -> SpeechEventConfig:
    """``fixture:tones`` model paths made the directory of the tones transducer."""
    built: Dict[str, Any] = {
        key: _tones_model() for key in PATH_KEYS if getattr(config, key) == FIXTURE_TONES
    }
    return dataclasses.replace(config, **built) if built else config


def engine_for(name: str, config: SpeechEventConfig) -> Tuple[str, SpeechEventConfig]:
    """The node's engine name and configuration for a scenario's recognizer.

    A fixture model is a real model directory: the node loads it as its NeMo model of both
    languages (as the fake serves both), of its family, in memory and on ROS alike.
    """
    config = _fixture_paths(config)
    if name == FIXTURE_MODEL:
        tones = _tones_model()
        return "nemo", dataclasses.replace(config, en_model_path=tones, rw_model_path=tones)
    if name == FIXTURE_PARAKEET:
        tdt = _tones_tdt_model()
        return "nemo", dataclasses.replace(config, model="parakeet", en_model_path=tdt, rw_model_path=tdt)
    if name == FIXTURE_WHISPER:
        whisper = _whisper_tones_model()
        return "whisper", dataclasses.replace(
            config, model="whisper", en_model_path=whisper, rw_model_path=whisper
        )
    return name, config


def recognizer_for(name: str, config: SpeechEventConfig) -> Recognizer:
    engine, engine_config = engine_for(name, config)
    return ENGINES[engine](engine_config)


def engine_builder_for(name: str, config: SpeechEventConfig) -> EngineBuilder:
    """How the node builds another language's engine (set_language) for a scenario's recognizer."""
    engine, engine_config = engine_for(name, config)
    return engine_builder(engine, engine_config)
