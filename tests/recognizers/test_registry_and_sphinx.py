"""The embedded English engine (pocketsphinx) in its three modes, and how the node picks its engine."""

from pathlib import Path

import numpy as np
import pytest

from fixtures.transducer_model import build_random_transducer
from fixtures.tts import speak_tts
from speech_event.config import SpeechEventConfig
from speech_event.errors import ModelError
from speech_event.recognizers import RECOGNIZERS
from speech_event.recognizers.nemo.recognizer import NemoRecognizer
from speech_event.recognizers.sphinx import SphinxRecognizer, phrases_to_jsgf
from tests.helpers.application import run_application
from tests.helpers.paths import ROOT

COMMANDS = ROOT / "harness" / "data" / "robot_commands.txt"


def test_phrases_compile_to_a_jsgf_grammar_of_exactly_those_sentences() -> None:
    assert phrases_to_jsgf(["# a comment", "Go  to the kitchen", "", "stop", "stop"]) == (
        "#JSGF V1.0;\ngrammar commands;\npublic <command> = ( go to the kitchen ) | ( stop );\n"
    )


@pytest.mark.parametrize(
    ("phrases", "message"),
    [
        (["# nothing"], "robot.txt: no phrases; write one command phrase a line"),
        (["turn 90 degrees"], "robot.txt: 'turn 90 degrees' has '90'; phrases are words of a-z and '"),
    ],
)
def test_a_bad_phrase_list_is_named(phrases: list, message: str) -> None:  # type: ignore[type-arg]
    with pytest.raises(ModelError) as error:
        phrases_to_jsgf(phrases, "robot.txt")
    assert str(error.value) == message


def test_grammar_mode_transcribes_every_robot_command_exactly() -> None:
    recognizer = SphinxRecognizer(grammar=str(COMMANDS))
    commands = [line for line in COMMANDS.read_text().splitlines() if line and not line.startswith("#")]
    assert [recognizer.transcribe(speak_tts(command, 16000)).text for command in commands] == commands


def test_a_jsgf_file_is_used_as_it_is(tmp_path: Path) -> None:
    grammar = tmp_path / "yes_no.jsgf"
    grammar.write_text("#JSGF V1.0;\ngrammar answers;\npublic <answer> = yes | no;\n")
    recognizer = SphinxRecognizer(grammar=str(grammar))
    assert recognizer.transcribe(speak_tts("no", 16000)).text == "no"


def test_a_grammar_word_missing_from_the_dictionary_is_named(tmp_path: Path) -> None:
    phrases = tmp_path / "robot.txt"
    phrases.write_text("go to the kitchen\nmuraho pepper\n")
    with pytest.raises(ModelError) as error:
        SphinxRecognizer(grammar=str(phrases))
    assert str(error.value) == f"{phrases}: words not in pocketsphinx's English dictionary: muraho"


def test_keyword_mode_reports_the_keyword_once() -> None:
    recognizer = SphinxRecognizer(keywords=str(ROOT / "config" / "robot_keywords.txt"))
    assert recognizer.transcribe(speak_tts("could you please help me pepper", 16000)).text == "pepper"
    assert recognizer.transcribe(speak_tts("go to the kitchen", 16000)).text == ""


def test_grammar_and_keywords_together_are_refused() -> None:
    with pytest.raises(ModelError) as error:
        SphinxRecognizer(grammar=str(COMMANDS), keywords=str(COMMANDS))
    assert str(error.value) == "set pocketsphinx_grammar or pocketsphinx_keywords, not both"


def test_auto_picks_pocketsphinx_for_english_without_a_model_and_nemo_with_one(tmp_path: Path) -> None:
    assert isinstance(RECOGNIZERS["auto"](SpeechEventConfig()), SphinxRecognizer)
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
    recognizer = SphinxRecognizer(grammar=str(COMMANDS))
    # Speech that is no command: pocketsphinx's best path ends inside a phrase ("go to the living").
    assert recognizer.transcribe(speak_tts("the weather is lovely in kigali today", 16000)).text == ""
