"""Speculative recognition (issue 11): the same texts as without it, never later.

The node runs twice on the same timeline of blocks, on the fake clock with the simulated worker
(each recognition takes ``recognition_seconds`` of clock time; a speculation is a recognition
too): once with speculative_recognition false, once true.
"""

import dataclasses
from typing import List, Tuple

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fixtures.audio import speak_tones
from fixtures.rig import Rig
from speech_event.adapters.executors import ClockExecutor
from speech_event.config import SpeechEventConfig
from speech_event.messages import Float32MultiArray
from speech_event.ports import Transcript
from speech_event.recognizers.tones import ToneRecognizer
from speech_event.turns.speculation import complete_answers, is_complete

RATE = 16000
PLAIN = SpeechEventConfig(sample_rate=RATE, health_check_period=3600.0, speculative_recognition=False)
SPECULATING = dataclasses.replace(PLAIN, speculative_recognition=True)


class AudioDigest:
    """Answers with what identifies the audio exactly: a different utterance, a different text."""

    sample_rate = RATE

    def __init__(self) -> None:
        self.calls = 0

    def transcribe(self, audio: np.ndarray) -> Transcript:
        self.calls += 1
        return Transcript(f"{audio.size} {float(np.sum(audio.astype(np.float64))):.6f}")

    def stop(self) -> None:
        """Stops at once (the simulated worker is free when a speculation is cancelled)."""


class Uncancellable:
    sample_rate = RATE

    def transcribe(self, audio: np.ndarray) -> Transcript:
        return Transcript("heard")


def _rounded(rig: Rig) -> List[Tuple[float, str]]:
    return [(round(time, 6), text) for time, text in rig.published]


def test_an_engine_that_cannot_be_stopped_is_not_speculated_with() -> None:
    rig = Rig(SPECULATING, Uncancellable(), job_seconds=1.0)
    rig.sound_detection.publish(Float32MultiArray(data=np.full(100, 0.1, dtype=np.float32)))
    rig.clock.advance(5.0)
    assert rig.node.speculations.started == 0


Block = Tuple[float, int]  # (seconds since the previous block, samples)

# Gaps inside words, around the speculation gap (0.3 s), and pauses that end utterances (1.5 s).
gaps = st.one_of(
    st.floats(0.01, 0.2), st.floats(0.25, 0.6), st.floats(0.9, 1.49), st.floats(1.5, 4.0), st.just(1.5)
)
timelines = st.lists(st.tuples(gaps, st.integers(1, 4096)), min_size=1, max_size=25)


def _published(
    config: SpeechEventConfig,
    timeline: List[Block],
    recognition_seconds: float,
) -> List[Tuple[float, str]]:
    rig = Rig(config, AudioDigest(), job_seconds=recognition_seconds)
    assert isinstance(rig.executor, ClockExecutor)
    rng = np.random.default_rng(7)
    for gap, size in timeline:
        rig.clock.advance(gap)
        rig.sound_detection.publish(Float32MultiArray(data=rng.uniform(-0.5, 0.5, size).astype(np.float32)))
    rig.clock.advance(config.speech_pause_period + 0.1)
    rig.clock.advance_to(max(rig.clock.now(), rig.executor.free_at) + 0.1)
    rig.node.stop()
    return rig.published


@settings(max_examples=300, deadline=None)
@given(timelines, st.sampled_from([0.0, 0.05, 0.2, 0.8, 1.3, 3.0]))
def test_with_speculation_the_same_texts_are_published_each_no_later(
    timeline: List[Block], recognition_seconds: float
) -> None:
    plain = _published(PLAIN, timeline, recognition_seconds)
    speculating = _published(SPECULATING, timeline, recognition_seconds)
    assert [text for _, text in speculating] == [text for _, text in plain]
    assert all(fast <= slow + 1e-9 for (fast, _), (slow, _) in zip(speculating, plain))


def test_a_speculation_done_in_the_pause_publishes_at_the_pause_not_after_a_recognition() -> None:
    timeline = [(0.1, 4096), (0.1, 4096)]  # one utterance: its last block at 0.2 s
    plain = _published(PLAIN, timeline, 0.8)
    speculating = _published(SPECULATING, timeline, 0.8)
    # without: the pause ends at 1.7 s, then 0.8 s of recognition; with: speculated from 0.5 s to 1.3 s
    assert [time for time, _ in plain] == [pytest.approx(2.5)]
    assert [time for time, _ in speculating] == [pytest.approx(1.7)]


def test_a_speculation_still_running_when_the_pause_ends_publishes_when_it_ends() -> None:
    timeline = [(0.1, 4096)]
    speculating = _published(SPECULATING, timeline, 3.0)  # speculated from 0.4 s: done at 3.4 s
    assert [time for time, _ in speculating] == [pytest.approx(3.4)]
    assert [time for time, _ in _published(PLAIN, timeline, 3.0)] == [pytest.approx(4.6)]


def _block(rig: Rig, value: float) -> None:
    rig.sound_detection.publish(Float32MultiArray(data=np.full(100, value, dtype=np.float32)))


def test_a_block_after_the_gap_cancels_the_speculation_and_the_worker_is_free_at_once() -> None:
    recognizer = AudioDigest()
    rig = Rig(SPECULATING, recognizer, job_seconds=1.0)
    assert isinstance(rig.executor, ClockExecutor)
    _block(rig, 0.1)
    rig.clock.advance(0.5)  # the gap passed at 0.3 s: a speculation runs until 1.3 s
    assert rig.node.speculations.started == 1
    _block(rig, 0.2)
    assert rig.executor.free_at == pytest.approx(0.5)  # cancelled: it never runs
    rig.clock.advance(5.0)
    assert recognizer.calls == 1  # the second speculation, used for the closed utterance
    assert (rig.node.speculations.started, rig.node.speculations.used) == (2, 1)


def _tones_published(config: SpeechEventConfig, said: List[Tuple[float, str]]) -> List[Tuple[float, str]]:
    """Words in the tones voice, each starting at its time: (time, text) published."""
    rig = Rig(config, ToneRecognizer())
    for start, text in said:
        rig.clock.advance_to(start)
        rig.speak(speak_tones(text, RATE) if text else np.zeros(4096, dtype=np.float32))
    rig.clock.advance(config.speech_pause_period + 0.1)
    rig.node.stop()
    return _rounded(rig)


EARLY = dataclasses.replace(SPECULATING, early_pause=0.5)


def _ends(text: str, start: float = 0.0) -> float:
    """When the last block of ``text`` said from ``start`` arrives."""
    return round(start + -(-speak_tones(text, RATE).size // 4096) * 4096 / RATE, 6)


def test_a_complete_answer_is_published_early_pause_after_the_speaker_stops() -> None:
    assert _tones_published(EARLY, [(0.0, "yes")]) == [(round(_ends("yes") + 0.5, 6), "yes")]
    assert _tones_published(SPECULATING, [(0.0, "yes")]) == [(round(_ends("yes") + 1.5, 6), "yes")]


def test_an_answer_not_known_to_be_complete_waits_the_whole_pause() -> None:
    assert _tones_published(EARLY, [(0.0, "go left")]) == [(round(_ends("go left") + 1.5, 6), "go left")]


def test_two_speculations_that_agree_end_the_turn_early() -> None:
    """The speaker goes quiet, a block of silence comes 0.4 s later: the second speculation says
    what the first said, so the answer is complete."""
    config = dataclasses.replace(EARLY, complete_answers="")
    silence_at = _ends("go left") + 0.4
    published = _tones_published(config, [(0.0, "go left"), (silence_at, "")])
    assert published == [(round(silence_at + 4096 / RATE + 0.5, 6), "go left")]


def test_speech_that_goes_on_after_an_early_publish_is_the_next_utterance() -> None:
    later = _ends("yes") + 0.7  # after the early publish at +0.5, within the whole pause
    published = _tones_published(EARLY, [(0.0, "yes"), (later, "please")])
    assert [text for _, text in published] == ["yes", "please"]


def test_completeness() -> None:
    answers = complete_answers(" Yes,no , yego,oya,")
    assert answers == frozenset({"yes", "no", "yego", "oya"})
    assert is_complete("Yego", None, False, answers)
    assert not is_complete("go left", None, False, answers)
    assert is_complete("go left", "go left", False, answers)
    assert is_complete("go left", None, True, answers)
    assert not is_complete("", "", True, answers)


def test_what_was_speculated_before_the_node_was_disabled_does_not_end_the_next_turn_early() -> None:
    """Agreement is between speculations on one utterance: a speculation on speech thrown away by
    set_enabled false is no evidence about the next one."""
    rig = Rig(dataclasses.replace(EARLY, complete_answers=""), ToneRecognizer())
    rig.speak(speak_tones("go left", RATE))
    rig.clock.advance(0.4)  # speculated: "go left"
    rig.node.set_enabled(False)
    rig.node.set_enabled(True)
    rig.speak(speak_tones("go left", RATE))
    last = rig.clock.now()
    rig.clock.advance(2.0)
    assert _rounded(rig) == [(round(last + 1.5, 6), "go left")]  # the whole pause: one speculation only
