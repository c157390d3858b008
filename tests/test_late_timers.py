"""A busy machine runs the node's timer thread late: the pause that ends an utterance is over, but
its timer has not fired when the next block or a service call comes. Where the utterance ends, and
with which engine, grammar and enabled state it is transcribed, must not depend on that."""

import dataclasses
from typing import Optional

import numpy as np

from fixtures.audio import speak_tones
from fixtures.fakes import Engines, SpyRecognizer
from fixtures.rig import AT_16K, Rig
from speech_event.adapters.fake_clock import FakeClock
from speech_event.interfaces.services import SET_ENABLED_SERVICE, SET_GRAMMAR_SERVICE, SET_LANGUAGE_SERVICE
from speech_event.messages import Float32MultiArray, SetEnabledRequest, SetGrammarRequest, SetLanguageRequest
from speech_event.ports import Recognizer
from speech_event.recognizers.tones import ToneRecognizer

BLOCK = np.full(4096, 0.1, dtype=np.float32)


class LateTimers(FakeClock):
    def pause_passes(self) -> None:
        """speech_pause_period passes while no timer fires: their thread is late."""
        self.late_by(AT_16K.speech_pause_period)

    def late_by(self, seconds: float) -> None:
        """``seconds`` pass while no timer fires."""
        self._now += seconds


def _rig(recognizer: Recognizer, engines: Optional[Engines] = None) -> Rig:
    return Rig(AT_16K, recognizer, clock=LateTimers(), build_engine=(engines or Engines()).build)


def _say(rig: Rig, samples: np.ndarray) -> None:
    """The node hears ``samples``; then the pause after them passes, its timer late."""
    rig.sound_detection.publish(Float32MultiArray(data=samples))
    assert isinstance(rig.clock, LateTimers)
    rig.clock.pause_passes()


def test_a_block_after_the_pause_starts_a_new_utterance() -> None:
    recognizer = SpyRecognizer()
    rig = _rig(recognizer)
    _say(rig, BLOCK)
    rig.sound_detection.publish(Float32MultiArray(data=BLOCK[:2048]))
    rig.clock.advance(5.0)
    assert [u.size for u in recognizer.utterances] == [4096, 2048]


def test_an_utterance_over_before_set_grammar_is_transcribed_with_the_old_grammar() -> None:
    rig = _rig(ToneRecognizer())
    assert rig.bus.call(SET_GRAMMAR_SERVICE, SetGrammarRequest("stop|go")).response == 1  # type: ignore[attr-defined]
    _say(rig, speak_tones("stop", 16000))
    assert rig.bus.call(SET_GRAMMAR_SERVICE, SetGrammarRequest("yes|no")).response == 1  # type: ignore[attr-defined]
    rig.clock.advance(5.0)
    assert rig.texts() == ["stop"]


def test_an_utterance_over_before_set_language_is_transcribed_by_the_old_engine() -> None:
    engines = Engines()
    rig = _rig(engines.spies["english"], engines)
    _say(rig, BLOCK)
    assert rig.bus.call(SET_LANGUAGE_SERVICE, SetLanguageRequest("kinyarwanda")).response == 1  # type: ignore[attr-defined]
    rig.clock.advance(5.0)
    assert rig.texts() == ["english"]


def test_an_utterance_over_before_set_enabled_false_is_transcribed_not_dropped() -> None:
    recognizer = SpyRecognizer()
    rig = _rig(recognizer)
    _say(rig, BLOCK)
    assert rig.bus.call(SET_ENABLED_SERVICE, SetEnabledRequest("false")).response == 1  # type: ignore[attr-defined]
    rig.clock.advance(5.0)
    assert [u.size for u in recognizer.utterances] == [4096]
    assert rig.texts() == ["heard"]


def test_in_free_speech_a_late_timer_thread_starts_no_speculation_that_end_of_speech_off_would_not() -> None:
    # end_of_speech left empty does not decide in free speech: no end of speech is heard when a
    # block comes 0.4 s after the one before while the timers are late (its 0.3 s are over), and
    # no speculation starts there to be stopped by that block at once.
    outcomes = []
    for config in (AT_16K, dataclasses.replace(AT_16K, end_of_speech=0.0)):
        assert config.grammar == ""
        rig = Rig(config, ToneRecognizer(), clock=LateTimers())
        rig.sound_detection.publish(Float32MultiArray(data=speak_tones("yes", 16000)))
        assert isinstance(rig.clock, LateTimers)
        rig.clock.late_by(0.4)
        rig.sound_detection.publish(Float32MultiArray(data=speak_tones("no", 16000)))
        rig.clock.advance(5.0)
        outcomes.append((rig.published, rig.node.speculations.started))
    assert outcomes[0] == outcomes[1]
