"""Recognizers: adapters of the Recognizer port, by the name a config or scenario gives."""

from typing import Callable, Dict

from speech_event.ports import Recognizer
from speech_event.recognizers.tones import ToneRecognizer

RECOGNIZERS: Dict[str, Callable[[], Recognizer]] = {"fake": ToneRecognizer}
