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


def test_each_later_cut_of_an_utterance_is_decided_but_after_the_first_none_is_speculated_on_before() -> None:
    end = EndOfTurn(CONFIG)
    assert not end.worth_speculating()  # no speech yet: no decision can come of it
    first = _spoken(end, "go")
    assert end.worth_speculating()
    assert end.speculation_cut(paused=True) == end.gap_end() == first
    _went_on(end, first)
    second = first + _spoken(end, "to the kitchen")
    assert end.gap_end() == second
    # The turn went on at the first: a person talking. The next end is decided when heard.
    assert end.speculation_cut(paused=True) is None
    assert not end.worth_speculating()
    end.decide(second)
    assert end.worth_speculating() and end.speculation_cut() == second  # the decision's own
    _went_on(end, second)
    end.closed(at_cut=False)  # the pause ended it: the next utterance is speculated on again
    assert not end.worth_speculating()
    stop = _spoken(end, "stop")
    assert end.worth_speculating() and end.speculation_cut(paused=True) == stop


def test_where_the_end_of_speech_does_not_decide_every_utterance_is_worth_speculating_on() -> None:
    end = EndOfTurn(CONFIG, decides=lambda: False)
    assert end.worth_speculating()
    _spoken(end, "go")
    assert end.worth_speculating() and end.speculation_cut(paused=True) is None
    off = EndOfTurn(dataclasses.replace(CONFIG, end_of_speech=0.0))
    assert off.worth_speculating()


def test_the_room_after_a_cut_is_not_worth_speculating_on_until_speech_is_heard_in_it() -> None:
    end = EndOfTurn(CONFIG, decides=lambda: False)  # not for want of a decision
    stop = _spoken(end, "stop")
    end.decide(stop)
    end.decided()
    end.closed(at_cut=True)
    room = np.random.default_rng(0).normal(0.0, 0.003, RATE // 2).astype(np.float32)
    end.heard(room)
    assert not end.worth_speculating() and not end.worth_transcribing()
    _spoken(end, "yes")
    assert end.worth_speculating() and end.worth_transcribing()


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
