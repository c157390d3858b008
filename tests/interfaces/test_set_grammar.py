"""/speechEvent/set_grammar and the grammar key on the in-memory bus, with the tones engine (which
takes a grammar as the real engines do: a phrase of it, or nothing and the nearest phrase rejected)."""

import dataclasses
import logging
from pathlib import Path
from typing import Dict

import pytest

from fixtures.audio import speak_tones
from fixtures.fakes import SpyRecognizer
from fixtures.rig import AT_16K, Rig
from speech_event.config import SpeechEventConfig
from speech_event.errors import ConfigError
from speech_event.interfaces.services import SET_GRAMMAR_SERVICE, SET_LANGUAGE_SERVICE
from speech_event.messages import SetGrammarRequest, SetLanguageRequest
from speech_event.recognizers.tones import ToneRecognizer
from speech_event.topics import SPEECH_NOT_RECOGNIZED

PAUSE = AT_16K.speech_pause_period + 0.1


def _grammar(rig: Rig, request: str) -> int:
    return int(rig.bus.call(SET_GRAMMAR_SERVICE, SetGrammarRequest(request)).response)  # type: ignore[attr-defined]


def _say(rig: Rig, text: str) -> None:
    rig.speak(speak_tones(text, 16000))
    rig.clock.advance(PAUSE)


def _diagnostics(rig: Rig) -> Dict[str, str]:
    """The key-values of the /diagnostics status published next."""
    rig.clock.advance(AT_16K.health_check_period)
    (status,) = rig.diagnostics[-1].status
    return {value.key: value.value for value in status.values}


def test_with_a_grammar_only_its_phrases_are_published_and_the_rest_is_counted() -> None:
    rig = Rig(AT_16K, ToneRecognizer())
    assert _grammar(rig, "yes|no") == 1
    for said in ("yes", "maybe", "no", "yess"):
        _say(rig, said)
    assert rig.texts() == ["yes", "no"]
    values = _diagnostics(rig)
    assert (values["grammar"], values["utterances out of grammar"]) == ("yes|no", "2")


def test_out_of_grammar_speech_is_said_as_not_recognized_with_publish_unrecognized() -> None:
    rig = Rig(dataclasses.replace(AT_16K, publish_unrecognized=True), ToneRecognizer())
    assert _grammar(rig, "yes|no") == 1
    _say(rig, "maybe")
    assert rig.texts() == [SPEECH_NOT_RECOGNIZED]


def test_an_empty_request_is_free_speech_again(caplog: pytest.LogCaptureFixture) -> None:
    rig = Rig(AT_16K, ToneRecognizer())
    caplog.set_level(logging.INFO, "speech_event")
    assert _grammar(rig, "yes|no") == 1
    _say(rig, "maybe")
    assert _grammar(rig, "") == 1
    _say(rig, "maybe")
    assert rig.texts() == ["maybe"]
    assert "speechEvent grammar: none (free speech)" in caplog.messages
    assert "utterance 1 (0.39 s) is no phrase of the grammar (nearest: 'yes') -> None" in caplog.messages


@pytest.mark.parametrize(
    ("request_text", "reason"),
    [
        ("go|4ward", "go|4ward: '4ward' has '4ward'; phrases are words of a-z and '"),
        (
            "/no/such/file.gram",
            "'/no/such/file.gram': no such grammar file; allowed: a JSGF or phrase file, phrases parted by | "
            "(words of a-z and '), or empty for free speech",
        ),
    ],
)
def test_a_request_that_cannot_be_used_answers_0_and_the_grammar_stays(
    caplog: pytest.LogCaptureFixture, request_text: str, reason: str
) -> None:
    rig = Rig(AT_16K, ToneRecognizer())
    assert _grammar(rig, "yes|no") == 1
    assert _grammar(rig, request_text) == 0
    assert caplog.messages[-1] == f"{SET_GRAMMAR_SERVICE}: {reason}"
    _say(rig, "maybe")
    _say(rig, "no")
    assert rig.texts() == ["no"]


def test_an_engine_that_takes_no_grammar_answers_0_saying_so(caplog: pytest.LogCaptureFixture) -> None:
    rig = Rig(AT_16K, SpyRecognizer())
    assert _grammar(rig, "yes|no") == 0
    assert caplog.messages[-1] == (
        f"{SET_GRAMMAR_SERVICE}: the SpyRecognizer engine takes no grammar; the grammar in force stays: "
        "none (free speech)"
    )


def test_utterances_closed_before_the_switch_finish_with_the_old_grammar() -> None:
    # Each recognition takes 1 s of the fake clock: "maybe" closes, waits, and is recognized after
    # the switch, yet with free speech, the grammar in force when it closed.
    rig = Rig(dataclasses.replace(AT_16K, speculative_recognition=False), ToneRecognizer(), job_seconds=1.0)
    rig.speak(speak_tones("maybe", 16000))
    rig.clock.advance(AT_16K.speech_pause_period + 0.01)
    assert rig.texts() == []
    assert _grammar(rig, "yes|no") == 1
    rig.speak(speak_tones("maybe", 16000))
    rig.clock.advance(PAUSE + 2.0)
    assert rig.texts() == ["maybe"]


def test_the_grammar_key_is_in_force_from_the_start(tmp_path: Path) -> None:
    path = tmp_path / "commands.txt"
    path.write_text("go left\nstop\n")
    rig = Rig(dataclasses.replace(AT_16K, grammar=str(path)), ToneRecognizer())
    assert rig.node.grammar is not None and rig.node.grammar.phrases == ("go left", "stop")
    _say(rig, "go right")
    _say(rig, "stop")
    assert rig.texts() == ["stop"]


def test_a_grammar_key_the_engine_cannot_take_stops_the_start(tmp_path: Path) -> None:
    path = tmp_path / "commands.txt"
    path.write_text("go left\n")
    with pytest.raises(ConfigError) as error:
        Rig(dataclasses.replace(AT_16K, grammar=str(path)), SpyRecognizer())
    assert str(error.value) == f"grammar {path}: the SpyRecognizer engine takes no grammar"


def test_a_language_whose_engine_cannot_take_the_grammar_in_force_is_refused(
    caplog: pytest.LogCaptureFixture,
) -> None:
    config = SpeechEventConfig(sample_rate=16000, health_check_period=3600.0)
    rig = Rig(config, ToneRecognizer(), build_engine=lambda language: SpyRecognizer())
    assert _grammar(rig, "yes|no") == 1
    assert int(rig.bus.call(SET_LANGUAGE_SERVICE, SetLanguageRequest("kinyarwanda")).response) == 0  # type: ignore[attr-defined]
    assert caplog.messages[-1] == (
        f"{SET_LANGUAGE_SERVICE}: cannot switch to kinyarwanda, staying with english: the SpyRecognizer "
        "engine takes no grammar"
    )
    assert _grammar(rig, "") == 1
    assert int(rig.bus.call(SET_LANGUAGE_SERVICE, SetLanguageRequest("kinyarwanda")).response) == 1  # type: ignore[attr-defined]
