"""Recognizers by name: adapters of the Recognizer port, built from the node's configuration.

``auto`` is what the robot runs: the model of the family ``model`` names (conformer-transducer,
parakeet: the NeMo engine; whisper: the Whisper engine) for the configured language when its path
is set, otherwise, for English with the default family, the embedded pocketsphinx engine. Engines
import their runtime only when chosen, so the node itself needs neither onnxruntime nor pocketsphinx.
Every engine is built with the ``grammar`` key's grammar and ``grammar_threshold``.
"""

import dataclasses
from pathlib import Path
from typing import Callable, Dict, Optional

from speech_event.config import SpeechEventConfig
from speech_event.errors import ModelError
from speech_event.grammar import Grammar, load_grammar
from speech_event.ports import EngineBuilder, Recognizer
from speech_event.recognizers.nemo.manifest import CONFORMER_TRANSDUCER, NEMO_FAMILIES
from speech_event.recognizers.onnx.directory import Runtime
from speech_event.recognizers.onnx.families import family_of
from speech_event.recognizers.tones import ToneRecognizer
from speech_event.recognizers.whisper.manifest import WHISPER

RecognizerFactory = Callable[[SpeechEventConfig], Recognizer]


def _model_directory(config: SpeechEventConfig) -> Path:
    """The configured language's model directory, which must be of the family ``model`` names."""
    key = "rw_model_path" if config.language == "kinyarwanda" else "en_model_path"
    path = getattr(config, key)
    if not path:
        exporter = "export-whisper CHECKPOINT" if config.model == WHISPER else "export-nemo MODEL.nemo"
        raise ModelError(
            f"language {config.language} with model {config.model} needs {key}: the directory of an "
            f"exported {config.model} model (speech-event {exporter} DIR writes one)"
        )
    directory = Path(path)
    family = family_of(directory, unrecorded=CONFORMER_TRANSDUCER)
    if directory.is_dir() and family != config.model:
        raise ModelError(
            f"{directory} holds a {family} model (config.json: family), but model is {config.model}: "
            f"set model {family}, or give a directory exported from a {config.model} model"
        )
    return directory


def runtime_of(config: SpeechEventConfig) -> Runtime:
    """How the ONNX engines run their files: the ``cuda`` and ``quantization`` keys."""
    return Runtime(cuda=config.cuda, int8=config.quantization == "int8")


def configured_grammar(config: SpeechEventConfig) -> Optional[Grammar]:
    """The ``grammar`` key's grammar; None for free speech; GrammarError (a ModelError) when unreadable."""
    return load_grammar(Path(config.grammar)) if config.grammar else None


def nemo(config: SpeechEventConfig) -> Recognizer:
    """The exported NeMo model of the configured language, of the family ``model`` names."""
    from speech_event.recognizers.nemo.recognizer import NemoRecognizer

    if config.model not in NEMO_FAMILIES:
        raise ModelError(f"model {config.model} is not a NeMo family ({', '.join(NEMO_FAMILIES)})")
    return NemoRecognizer(
        _model_directory(config), runtime_of(config), configured_grammar(config), config.grammar_threshold
    )


def whisper(config: SpeechEventConfig) -> Recognizer:
    """The exported Whisper model of the configured language (model whisper)."""
    from speech_event.recognizers.whisper.recognizer import WhisperRecognizer

    if config.model != WHISPER:
        raise ModelError(f"the whisper engine needs model whisper; model is {config.model}")
    return WhisperRecognizer(
        _model_directory(config),
        config.language,
        runtime_of(config),
        configured_grammar(config),
        config.grammar_threshold,
    )


def pocketsphinx(config: SpeechEventConfig) -> Recognizer:
    """The embedded pocketsphinx engine (English only), with the configured grammar or keyword list,
    in a process of its own (sphinx_process.py: it would stall the node's threads)."""
    from speech_event.recognizers.sphinx_process import SphinxProcess

    _check_english(config)
    return SphinxProcess(configured_grammar(config), config.pocketsphinx_keywords, config.grammar_threshold)


def pocketsphinx_in_process(config: SpeechEventConfig) -> Recognizer:
    """pocketsphinx in the caller's process: for a node on a simulated clock and worker (the
    scenarios in memory), where nothing runs beside a recognition for it to stall."""
    from speech_event.recognizers.sphinx import SphinxRecognizer

    _check_english(config)
    return SphinxRecognizer(
        configured_grammar(config), config.pocketsphinx_keywords, config.grammar_threshold
    )


def _check_english(config: SpeechEventConfig) -> None:
    if config.language != "english":
        raise ModelError(f"pocketsphinx transcribes English only; language is {config.language}")


def automatic(english: RecognizerFactory) -> RecognizerFactory:
    """``auto`` with ``english`` as its embedded English engine."""

    def auto(config: SpeechEventConfig) -> Recognizer:
        """The model of the family ``model`` names; the embedded engine for English without a model
        of the default family. Never falls back silently from another family asked for."""
        if config.model == WHISPER:
            return whisper(config)
        if config.language == "english" and not config.en_model_path and config.model == CONFORMER_TRANSDUCER:
            return english(config)
        return nemo(config)

    return auto


def recognizers(embedded: RecognizerFactory) -> Dict[str, RecognizerFactory]:
    """The engines by name, ``embedded`` the pocketsphinx engine's factory."""
    return {
        "auto": automatic(embedded),
        "nemo": nemo,
        "whisper": whisper,
        "pocketsphinx": embedded,
        "fake": lambda config: ToneRecognizer(configured_grammar(config)),
    }


RECOGNIZERS = recognizers(pocketsphinx)
# On a simulated clock and worker: pocketsphinx in the caller's process, saving its start.
SIMULATED_RECOGNIZERS = recognizers(pocketsphinx_in_process)


def engine_builder(name: str, config: SpeechEventConfig) -> EngineBuilder:
    """Builds engine ``name`` for another language with the same configuration (set_language)."""
    return lambda language: RECOGNIZERS[name](dataclasses.replace(config, language=language))
