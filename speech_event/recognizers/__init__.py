"""Recognizers by name: adapters of the Recognizer port, built from the node's configuration.

``auto`` is what the robot runs: the NeMo model of the configured language when its path is set,
otherwise, for English, the embedded pocketsphinx engine. Engines import their runtime only when
chosen, so the node itself needs neither onnxruntime nor pocketsphinx.
"""

import dataclasses
from typing import Callable, Dict

from speech_event.asr.errors import ModelError
from speech_event.config import SpeechEventConfig
from speech_event.engines import EngineBuilder
from speech_event.ports import Recognizer
from speech_event.recognizers.tones import ToneRecognizer

RecognizerFactory = Callable[[SpeechEventConfig], Recognizer]


NEMO_FAMILIES = ("conformer-transducer", "parakeet")


def _nemo_family(config: SpeechEventConfig) -> None:
    if config.model not in NEMO_FAMILIES:
        raise ModelError(
            f"model {config.model}: this release runs the conformer-transducer and parakeet families; "
            f"the {config.model} engine is not available yet"
        )


def nemo(config: SpeechEventConfig) -> Recognizer:
    """The exported NeMo model of the configured language, of the family ``model`` names."""
    from speech_event.asr.engine import NemoRecognizer

    _nemo_family(config)
    key = "rw_model_path" if config.language == "kinyarwanda" else "en_model_path"
    path = getattr(config, key)
    if not path:
        raise ModelError(
            f"language {config.language} with model {config.model} needs {key}: the directory of an "
            "exported NeMo model (speech-event export-nemo MODEL.nemo DIR writes one)"
        )
    return NemoRecognizer(path, config.cuda, family=config.model)


def pocketsphinx(config: SpeechEventConfig) -> Recognizer:
    from speech_event.recognizers.sphinx import SphinxRecognizer

    if config.language != "english":
        raise ModelError(f"pocketsphinx transcribes English only; language is {config.language}")
    return SphinxRecognizer(config.pocketsphinx_grammar, config.pocketsphinx_keywords)


def auto(config: SpeechEventConfig) -> Recognizer:
    """pocketsphinx for English without a model of the default family; otherwise the model. Never
    falls back silently from another family asked for."""
    _nemo_family(config)
    if config.language == "english" and not config.en_model_path and config.model == "conformer-transducer":
        return pocketsphinx(config)
    return nemo(config)


RECOGNIZERS: Dict[str, RecognizerFactory] = {
    "auto": auto,
    "nemo": nemo,
    "pocketsphinx": pocketsphinx,
    "fake": lambda config: ToneRecognizer(),
}


def engine_builder(name: str, config: SpeechEventConfig) -> EngineBuilder:
    """Builds engine ``name`` for another language with the same configuration (set_language)."""
    return lambda language: RECOGNIZERS[name](dataclasses.replace(config, language=language))
