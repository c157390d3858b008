"""bench/figures/grammar_cost.py's grammars and its account of where a recognition's CPU goes."""

import time

import numpy as np

from bench.figures.grammar import OUT_OF_GRAMMAR, lines
from bench.figures.grammar_cost import SAID_COMMANDS, WhereTheTimeGoes, grammars
from bench.figures.measures import robot_commands
from speech_event.recognizers.whisper import forced, model, recognizer


def test_the_grammars_are_free_speech_yes_no_the_robots_commands_and_a_hundred_phrases() -> None:
    chosen = grammars()
    assert list(chosen) == ["none", "yes|no", "32 commands", "100 phrases"]
    assert chosen["none"] == "" and chosen["yes|no"] == "yes|no"
    commands = chosen["32 commands"].split("|")
    assert commands == robot_commands() and len(commands) == 32
    hundred = chosen["100 phrases"].split("|")
    assert len(hundred) == len(set(hundred)) == 100 and hundred[:32] == commands
    # what the voice says outside the grammars is in none of them, and its commands in the two big ones
    outside = lines(OUT_OF_GRAMMAR)[-8:]
    assert not set(outside) & set(hundred)
    assert set(SAID_COMMANDS) <= set(commands)


class _Engine:
    def transcribe(self, audio: np.ndarray) -> object:
        model.WhisperModel.encode(None, audio)  # type: ignore[arg-type]
        return audio.size


def test_the_parts_are_timed_while_counting_and_the_engine_is_left_as_it_was() -> None:
    originals = (
        vars(model.WhisperModel)["encode"],
        vars(recognizer)["whisper_greedy"],
        forced.UnheardScores.__call__,
    )
    engine = _Engine()
    parts = WhereTheTimeGoes()
    busy_until = [0.0]

    def encode(self: object, audio: np.ndarray) -> None:
        busy_until[0] = time.process_time() + 0.02
        while time.process_time() < busy_until[0]:  # CPU time, which the bench counts
            pass

    model.WhisperModel.encode = encode  # type: ignore[assignment,method-assign]
    try:
        with parts.counting(engine):  # type: ignore[arg-type]
            assert engine.transcribe(np.zeros(3)) == 3
            assert engine.transcribe(np.zeros(4)) == 4
        assert parts.transcriptions == 2
        assert list(parts.seconds) == ["encoder"] and parts.seconds["encoder"] >= 0.04
        assert vars(model.WhisperModel)["encode"] is encode
        assert "transcribe" not in vars(engine)
    finally:
        model.WhisperModel.encode = originals[0]  # type: ignore[method-assign]
    assert (vars(recognizer)["whisper_greedy"], forced.UnheardScores.__call__) == originals[1:]
