"""EndOfTurn alone (speech_event/turns/end_of_turn.py): which cuts of an utterance are decided."""

import dataclasses

import numpy as np

from fixtures.audio import speak_tones
from fixtures.rig import AT_16K
from speech_event.turns.end_of_turn import EndOfTurn

RATE = 16000
CONFIG = dataclasses.replace(AT_16K, end_of_speech=0.3)


def _went_on(end: EndOfTurn, cut: int) -> None:
    """A decision on ``cut`` that let the turn go on."""
    end.decide(cut)
    assert end.decided() == []


def _spoken(end: EndOfTurn, words: str) -> int:
    samples = speak_tones(words, RATE).astype(np.float32)
    end.heard(samples)
    return samples.size


def test_each_later_cut_of_an_utterance_is_decided() -> None:
    end = EndOfTurn(CONFIG)
    first = _spoken(end, "go")
    assert end.gap_end() == first
    _went_on(end, first)
    second = first + _spoken(end, "to the kitchen")
    assert end.speculation_cut(paused=True) == end.gap_end() == second


def test_with_an_engine_that_decides_once_only_the_first_cut_of_an_utterance_is_decided() -> None:
    end = EndOfTurn(CONFIG, decides_once=lambda: True)
    first = _spoken(end, "go")
    assert end.gap_end() == first
    _went_on(end, first)
    _spoken(end, "to the kitchen")
    assert end.speculation_cut(paused=True) is None
    assert end.gap_end() is None
    end.closed(at_cut=False)  # the pause ended it: the next utterance is decided again
    assert end.gap_end() is None  # nothing heard of it yet
    stop = _spoken(end, "stop")
    assert end.gap_end() == stop
