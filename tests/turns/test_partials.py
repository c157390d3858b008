"""Partial results (issue 20): the text so far on /speechEvent/partial, and every text on
/speechEvent/transcript, without any change to the final texts.

The node runs on the fake clock with the simulated worker (each recognition, partial runs and
feeds included, takes ``recognition_seconds`` of clock time)."""

import dataclasses
from typing import List, Optional, Tuple

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fixtures.audio import speak_tones
from fixtures.rig import Rig
from speech_event import SOUND_DETECTION_DOWN
from speech_event.config import SpeechEventConfig, parse_config
from speech_event.errors import ConfigError
from speech_event.grammar import Grammar
from speech_event.messages import NO_CONFIDENCE, NO_UTTERANCE, Float32MultiArray, String, TranscriptMessage
from speech_event.ports import Transcript
from speech_event.recognizers.tones import ToneRecognizer
from speech_event.topics import PARTIAL_TOPIC, TRANSCRIPT_TOPIC

RATE = 16000
BLOCK = 4096 / RATE  # Rig.speak: one block every 0.256 s, the first at 0.256 s
PLAIN = SpeechEventConfig(sample_rate=RATE, health_check_period=3600.0, partial_period=0.0)
PARTIALS = dataclasses.replace(PLAIN, partial_period=0.5)


class Listener:
    """What the node published on the partial and transcript topics, with the clock's time."""

    def __init__(self, rig: Rig) -> None:
        self.partials: List[Tuple[float, str]] = []
        self.transcripts: List[TranscriptMessage] = []
        rig.bus.subscribe(PARTIAL_TOPIC, String, lambda m: self.partials.append((rig.clock.now(), m.data)))  # type: ignore[attr-defined]
        rig.bus.subscribe(TRANSCRIPT_TOPIC, TranscriptMessage, self.transcripts.append)  # type: ignore[arg-type]

    def timed(self) -> List[Tuple[float, str]]:
        return [(round(time, 6), text) for time, text in self.partials]


class AudioDigest:
    """Answers with what identifies the audio exactly: a different utterance, a different text."""

    sample_rate = RATE

    def transcribe(self, audio: np.ndarray) -> Transcript:
        return Transcript(f"{audio.size} {float(np.sum(audio.astype(np.float64))):.6f}")

    def stop(self) -> None:
        """Stops at once (the simulated worker is free when a run is cancelled)."""


class IncrementalDigest:
    """An Incremental engine that cannot be stopped: its partial decoder sums what it is fed, its
    final texts identify the whole utterance. Records every call."""

    sample_rate = RATE

    def __init__(self) -> None:
        self.calls: List[str] = []
        self.fed: List[np.ndarray] = []

    def transcribe(self, audio: np.ndarray) -> Transcript:
        self.calls.append(f"transcribe {audio.size}")
        return Transcript(f"{audio.size} {float(np.sum(audio.astype(np.float64))):.6f}")

    def begin_partial(self, grammar: Optional[Grammar]) -> None:
        self.calls.append("begin")
        self.fed = []

    def feed_partial(self, audio: np.ndarray) -> Transcript:
        self.calls.append(f"feed {audio.size}")
        self.fed.append(audio.copy())
        return Transcript(f"so far {sum(piece.size for piece in self.fed)}")


Block = Tuple[float, int]  # (seconds since the previous block, samples)

# Gaps inside words, around the speculation gap (0.3 s) and the partial period (0.5 s), and
# pauses that end utterances (1.5 s).
gaps = st.one_of(
    st.floats(0.01, 0.2), st.floats(0.25, 0.6), st.floats(0.9, 1.49), st.floats(1.5, 4.0), st.just(1.5)
)
timelines = st.lists(st.tuples(gaps, st.integers(1, 4096)), min_size=1, max_size=25)


def _run(config: SpeechEventConfig, engine: object, timeline: List[Block], seconds: float) -> Rig:
    rig = Rig(config, engine, job_seconds=seconds)  # type: ignore[arg-type]
    rng = np.random.default_rng(7)
    for gap, size in timeline:
        rig.clock.advance(gap)
        rig.sound_detection.publish(Float32MultiArray(data=rng.uniform(-0.5, 0.5, size).astype(np.float32)))
    rig.clock.advance(config.speech_pause_period + 0.1)
    rig.clock.advance_to(max(rig.clock.now(), rig.executor.free_at) + 0.1)  # type: ignore[attr-defined]
    rig.node.stop()
    return rig


@settings(max_examples=200, deadline=None)
@given(
    timelines,
    st.sampled_from([0.0, 0.05, 0.2, 0.8, 1.3]),
    st.booleans(),
    st.sampled_from(["stoppable", "incremental"]),
)
def test_with_partials_the_same_final_texts_are_published_at_the_same_times(
    timeline: List[Block], recognition_seconds: float, speculating: bool, engine: str
) -> None:
    plain = dataclasses.replace(PLAIN, speculative_recognition=speculating)
    with_partials = dataclasses.replace(plain, partial_period=0.5)

    def make() -> object:
        return AudioDigest() if engine == "stoppable" else IncrementalDigest()

    without = _run(plain, make(), timeline, recognition_seconds).published
    assert _run(with_partials, make(), timeline, recognition_seconds).published == without


def test_the_text_so_far_comes_every_period_and_only_when_it_changed() -> None:
    rig = Rig(PARTIALS, ToneRecognizer())
    listener = Listener(rig)
    rig.speak(speak_tones("go to the kitchen", RATE))  # blocks at 0.256 .. 1.024 s
    rig.clock.advance(3.0)
    # Due 0.5 s after the first block, then 0.5 s after each partial; at 1.324 s the speculation
    # heard all of it: the same text as the partial before, so nothing new.
    assert listener.timed() == [(0.756, "go to th"), (1.256, "go to the kitchen")]
    assert [(round(time, 6), text) for time, text in rig.published] == [(2.524, "go to the kitchen")]
    assert (rig.node.partials.started, rig.node.partials.published) == (2, 2)


def test_a_speculation_that_hears_more_than_the_last_partial_is_published_as_a_partial() -> None:
    rig = Rig(dataclasses.replace(PARTIALS, partial_period=2.0), ToneRecognizer())
    listener = Listener(rig)
    rig.speak(speak_tones("go left", RATE))
    last = rig.clock.now()  # the last block: 0.512 s
    rig.clock.advance(3.0)
    assert listener.timed() == [(round(last + 0.3, 6), "go left")]  # the speculation's text
    assert rig.node.partials.started == 0


def test_with_partials_off_nothing_is_published_on_their_topics() -> None:
    rig = Rig(PLAIN, ToneRecognizer())
    listener = Listener(rig)
    rig.speak(speak_tones("go to the kitchen", RATE))
    rig.clock.advance(3.0)
    assert listener.partials == []
    assert [(m.text, m.final) for m in listener.transcripts] == [("go to the kitchen", True)]


def test_a_partial_waits_for_the_worker_and_a_closing_utterance_cancels_it() -> None:
    engine = AudioDigest()
    config = dataclasses.replace(PARTIALS, speculative_recognition=False)
    rig = Rig(config, engine, job_seconds=2.0)
    listener = Listener(rig)
    block = Float32MultiArray(data=np.full(1600, 0.1, dtype=np.float32))
    rig.sound_detection.publish(block)  # utterance 1 at 0 s: closes at 1.5 s, recognized until 3.5 s
    rig.clock.advance(1.6)
    for _ in range(10):  # utterance 2: a block every 0.2 s from 1.6 to 3.4 s
        rig.sound_detection.publish(block)
        rig.clock.advance(0.2)
    # Utterance 1's partial ran from 0.5 s: its close at 1.5 s cancelled it. Utterance 2's was due
    # at 2.1 s, but the worker is busy until 3.5 s: it starts then, on 10 blocks, and would end at
    # 5.5 s; the pause ends at 3.4 + 1.5 = 4.9 s and cancels it.
    assert rig.node.partials.started == 2
    rig.clock.advance(10.0)
    assert listener.partials == []
    assert [round(time, 6) for time, _ in rig.published] == [3.5, 6.9]  # 4.9 s + 2 s, not 5.5 + 2


def test_an_incremental_engine_is_fed_only_new_audio_on_its_own_decoder() -> None:
    engine = IncrementalDigest()
    # the engine's own writing: its texts count samples in digits
    rig = Rig(dataclasses.replace(PARTIALS, speculative_recognition=False, text_style="engine"), engine)
    listener = Listener(rig)
    samples = np.arange(4096 * 5, dtype=np.float32) / 4096 / 5
    rig.speak(samples)  # blocks at 0.256 .. 1.28 s
    rig.clock.advance(3.0)
    # At 0.756 s the first two blocks, at 1.256 s the two since, at 1.756 s the last one; each fed
    # in chunks of 0.1 s (1600 samples).
    assert engine.calls == [
        "begin",
        *["feed 1600"] * 5,
        "feed 192",
        *["feed 1600"] * 5,
        "feed 192",
        *["feed 1600"] * 2,
        "feed 896",
        "transcribe 20480",
    ]
    assert np.array_equal(np.concatenate(engine.fed), samples)
    assert listener.timed() == [(0.756, "so far 8192"), (1.256, "so far 16384"), (1.756, "so far 20480")]
    assert [text for _, text in rig.published] == [IncrementalDigest().transcribe(samples).text]


def test_a_transcript_message_comes_with_each_partial_and_each_final_text() -> None:
    rig = Rig(PARTIALS, ToneRecognizer())
    listener = Listener(rig)
    rig.speak(speak_tones("go to the kitchen", RATE))
    rig.clock.advance(3.0)
    first, last = BLOCK, 4 * BLOCK
    stamped = [dataclasses.replace(m, stamp=round(m.stamp, 6)) for m in listener.transcripts]
    assert stamped == [
        TranscriptMessage(
            0.756, "go to th", False, NO_CONFIDENCE, "english", "ToneRecognizer", first, 2 * BLOCK
        ),
        TranscriptMessage(
            1.256, "go to the kitchen", False, NO_CONFIDENCE, "english", "ToneRecognizer", first, last
        ),
        TranscriptMessage(
            2.524,
            "go to the kitchen",
            True,
            NO_CONFIDENCE,
            "english",
            "ToneRecognizer",
            first,
            last,
        ),
    ]


class Confident:
    sample_rate = RATE

    def transcribe(self, audio: np.ndarray) -> Transcript:
        return Transcript("yes", 0.75)

    def stop(self) -> None:
        """Nothing runs long."""


def test_the_transcript_carries_the_engines_confidence_and_errors_carry_none() -> None:
    rig = Rig(dataclasses.replace(PARTIALS, language="kinyarwanda", health_check_period=1.0), Confident())
    listener = Listener(rig)
    rig.sound_detection.publish(Float32MultiArray(data=np.full(4096, 0.1, dtype=np.float32)))
    rig.clock.advance(1.6)
    rig.sound_detection.shutdown()
    rig.clock.advance(1.0)
    assert [
        (m.text, m.final, m.confidence, m.language, m.engine, m.first_block, m.last_block)
        for m in listener.transcripts
    ] == [
        ("yes", False, 0.75, "kinyarwanda", "Confident", 0.0, 0.0),  # the speculation at 0.3 s
        ("yes", True, 0.75, "kinyarwanda", "Confident", 0.0, 0.0),
        (SOUND_DETECTION_DOWN, True, NO_CONFIDENCE, "kinyarwanda", "Confident", NO_UTTERANCE, NO_UTTERANCE),
    ]


def test_a_partial_below_the_confidence_threshold_is_not_published() -> None:
    rig = Rig(dataclasses.replace(PARTIALS, confidence=0.8), Confident())
    listener = Listener(rig)
    rig.sound_detection.publish(Float32MultiArray(data=np.full(4096, 0.1, dtype=np.float32)))
    rig.clock.advance(3.0)
    assert listener.partials == []


@pytest.mark.parametrize(
    "value, message",
    [
        ("0.05", "f.ini: partial_period 0.05 s is too short: 0 (partial results off) or from 0.1 to 60 s"),
        (
            "61",
            "f.ini:1: key 'partial_period': value '61' is out of range; allowed: a number of seconds from 0.0 to 60.0",
        ),
    ],
)
def test_a_partial_period_out_of_range_is_refused_naming_what_is_allowed(value: str, message: str) -> None:
    with pytest.raises(ConfigError) as error:
        parse_config(f"partial_period {value}", "f.ini")
    assert str(error.value) == message
