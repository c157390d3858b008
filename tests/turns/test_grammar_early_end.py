"""Early end of turn in grammar mode: with a grammar in force, an engine that can be stopped ends
the turn ``early_pause`` after a whole phrase, on the tones engine and the real NeMo and Whisper
engines over the tones models."""

import dataclasses
from typing import Callable, List, Tuple

import pytest

from fixtures.audio import speak_tones
from fixtures.rig import AT_16K, Rig
from fixtures.tones_model import tones_ctc_model_directory, tones_model_directory, tones_tdt_model_directory
from fixtures.whisper_tones_model import whisper_tones_model_directory
from speech_event.interfaces.services import SET_GRAMMAR_SERVICE
from speech_event.messages import SetGrammarRequest
from speech_event.ports import Recognizer
from speech_event.recognizers.nemo.recognizer import NemoRecognizer
from speech_event.recognizers.tones import ToneRecognizer
from speech_event.recognizers.whisper.recognizer import WhisperRecognizer

CONFIG = dataclasses.replace(AT_16K, early_pause=0.5, complete_answers="")
COMMANDS = "go to the kitchen|stop|yes|no"
ENGINES: List[Tuple[str, Callable[[], Recognizer]]] = [
    ("tones", ToneRecognizer),
    ("nemo_rnnt", lambda: NemoRecognizer(tones_model_directory())),
    ("nemo_tdt", lambda: NemoRecognizer(tones_tdt_model_directory())),
    ("nemo_ctc", lambda: NemoRecognizer(tones_ctc_model_directory())),
    ("whisper", lambda: WhisperRecognizer(whisper_tones_model_directory(), "english")),
]


def _published_after_last_block(engine: Recognizer, grammar: str, said: str) -> List[Tuple[float, str]]:
    """What the node published for ``said``, timed from its last block."""
    rig = Rig(CONFIG, engine)
    if grammar:
        assert rig.bus.call(SET_GRAMMAR_SERVICE, SetGrammarRequest(grammar)).response == 1  # type: ignore[attr-defined]
    rig.speak(speak_tones(said, 16000))
    last_block = rig.clock.now()
    rig.clock.advance(CONFIG.speech_pause_period + 0.5)
    return [(round(when - last_block, 3), text) for when, text in rig.published]


@pytest.mark.parametrize(("name", "build"), ENGINES, ids=[name for name, _ in ENGINES])
def test_a_phrase_of_the_grammar_ends_the_turn_after_early_pause(
    name: str, build: Callable[[], Recognizer]
) -> None:
    assert _published_after_last_block(build(), COMMANDS, "stop") == [(0.5, "stop")]


@pytest.mark.parametrize(("name", "build"), ENGINES, ids=[name for name, _ in ENGINES])
def test_without_a_grammar_the_same_speech_waits_for_the_whole_pause(
    name: str, build: Callable[[], Recognizer]
) -> None:
    assert _published_after_last_block(build(), "", "stop") == [(CONFIG.speech_pause_period, "stop")]


@pytest.mark.parametrize(("name", "build"), ENGINES, ids=[name for name, _ in ENGINES])
def test_speech_outside_the_grammar_ends_no_turn_early_and_is_not_published(
    name: str, build: Callable[[], Recognizer]
) -> None:
    assert _published_after_last_block(build(), COMMANDS, "stops") == []
