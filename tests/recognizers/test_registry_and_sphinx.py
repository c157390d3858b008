"""The embedded English engine (pocketsphinx): its keyword mode, and how the node picks its engine
(its grammar mode: test_sphinx_grammar.py)."""

from pathlib import Path

import numpy as np
import pytest

from fixtures.application import run_application
from fixtures.paths import ROOT
from fixtures.transducer_model import build_random_transducer
from fixtures.tts import speak_tts
from speech_event.config import SpeechEventConfig
from speech_event.errors import ModelError
from speech_event.grammar import load_grammar
from speech_event.ports import Transcript
from speech_event.recognizers import RECOGNIZERS
from speech_event.recognizers.nemo.recognizer import NemoRecognizer
from speech_event.recognizers.sphinx import SphinxRecognizer
from speech_event.recognizers.sphinx_process import SphinxProcess

COMMANDS = ROOT / "harness" / "data" / "robot_commands.txt"


def test_keyword_mode_reports_the_keyword_once() -> None:
    recognizer = SphinxRecognizer(keywords=str(ROOT / "config" / "robot_keywords.txt"))
    assert recognizer.transcribe(speak_tts("could you please help me pepper", 16000)).text == "pepper"
    assert recognizer.transcribe(speak_tts("go to the kitchen", 16000)).text == ""


def test_grammar_and_keywords_together_are_refused() -> None:
    with pytest.raises(ModelError) as error:
        SphinxRecognizer(load_grammar(COMMANDS), keywords=str(COMMANDS))
    assert str(error.value) == "set grammar or pocketsphinx_keywords, not both"


def test_a_missing_keyword_list_is_named(tmp_path: Path) -> None:
    with pytest.raises(ModelError) as error:
        SphinxRecognizer(keywords=str(tmp_path / "keywords.txt"))
    assert str(error.value) == f"{tmp_path / 'keywords.txt'}: no such keyword list (pocketsphinx_keywords)"


def test_auto_picks_pocketsphinx_for_english_without_a_model_and_nemo_with_one(tmp_path: Path) -> None:
    sphinx = RECOGNIZERS["auto"](SpeechEventConfig())
    assert isinstance(sphinx, SphinxProcess)  # in a process of its own: test_sphinx_process.py
    sphinx.close()
    model = build_random_transducer(tmp_path / "en")
    chosen = RECOGNIZERS["auto"](SpeechEventConfig(en_model_path=str(model)))
    assert isinstance(chosen, NemoRecognizer)
    rw = RECOGNIZERS["auto"](SpeechEventConfig(language="kinyarwanda", rw_model_path=str(model)))
    assert isinstance(rw, NemoRecognizer)
    assert (
        rw.transcribe(np.zeros(16000, np.float32)).text == chosen.transcribe(np.zeros(16000, np.float32)).text
    )


def test_kinyarwanda_without_a_model_stops_the_node_with_status_2(tmp_path: Path) -> None:
    config = tmp_path / "rw.ini"
    config.write_text("language kinyarwanda\n")
    result = run_application("-c", str(config))
    assert result.returncode == 2
    assert result.stderr == (
        "error: language kinyarwanda with model conformer-transducer needs rw_model_path: the directory of an "
        "exported conformer-transducer model (speech-event export-nemo MODEL.nemo DIR writes one)\n"
    )


def test_a_phrase_grammar_publishes_only_whole_phrases() -> None:
    recognizer = SphinxRecognizer(load_grammar(COMMANDS))
    # Speech that is no command: once "go to the living" (pocketsphinx's best path stopped inside a
    # phrase); now only paths through a whole phrase count, and the nearest is rejected.
    transcript = recognizer.transcribe(speak_tts("the weather is lovely in kigali today", 16000))
    assert transcript == Transcript("", rejected="go to the living room")
