"""Where the speech ended, heard in the samples alone (speech_event/turns/speech_end.py)."""

from typing import List, Optional, Tuple

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from fixtures.audio import noise
from speech_event.turns.speech_end import AVERAGED_FRAMES, PAD_SECONDS, SpeechEnds

RATE = 16000
FRAME = 320  # 20 ms
HANGOVER = 0.3  # 15 frames


def _tone(seconds: float, amplitude: float) -> np.ndarray:
    t = np.arange(int(seconds * RATE)) / RATE
    return (amplitude * np.sin(2 * np.pi * 440 * t)).astype(np.float32)


def _room(seconds: float, seed: int = 1) -> np.ndarray:
    return noise(int(seconds * RATE), -50.0, np.random.default_rng(seed))


# 0.5 s of room, a word from 8000 to 12800 (frames 25 to 39), then the room again. Averaged over
# 5 frames, the word's last frame makes the next two speech too: the speech ends after frame 41.
WORD = np.concatenate([_room(0.5), _tone(0.3, 0.5), _room(1.0, seed=2)])
SPEECH_ENDS_AT = (39 + AVERAGED_FRAMES // 2 + 1) * FRAME
CUT = SPEECH_ENDS_AT + int(PAD_SECONDS * RATE)
HEARD_AT = SPEECH_ENDS_AT + 15 * FRAME  # the samples it takes to hear 15 frames after the speech


def _first_end(audio: np.ndarray, blocks: List[int]) -> Optional[Tuple[int, int]]:
    """(samples taken, cut) when heard_end first gives a cut, feeding ``audio`` in these blocks."""
    ends = SpeechEnds(RATE, HANGOVER)
    start = 0
    for size in [*blocks, audio.size]:
        ends.add(audio[start : start + size])
        start += size
        cut = ends.heard_end()
        if cut is not None:
            return ends.samples, cut
        if start >= audio.size:
            return None
    return None


def test_the_end_is_heard_hangover_after_the_last_speech_frame_and_cut_pad_after_it() -> None:
    assert _first_end(WORD, [FRAME] * 200) == (HEARD_AT, CUT)


def test_one_frame_short_of_the_hangover_is_no_end_yet() -> None:
    ends = SpeechEnds(RATE, HANGOVER)
    ends.add(WORD[: HEARD_AT - 1])
    assert ends.heard_speech()
    assert ends.end() == CUT
    assert ends.heard_end() is None


@settings(max_examples=60, deadline=None)
@given(st.lists(st.integers(1, 6000), min_size=1, max_size=40))
def test_the_cut_is_the_same_whatever_blocks_the_audio_came_in(blocks: List[int]) -> None:
    taken, cut = _first_end(WORD, blocks) or (0, 0)
    assert cut == CUT
    assert HEARD_AT <= taken < HEARD_AT + max([*blocks, WORD.size])


def test_room_noise_alone_is_no_speech() -> None:
    ends = SpeechEnds(RATE, HANGOVER)
    ends.add(_room(3.0))
    assert not ends.heard_speech()
    assert ends.end() is None and ends.heard_end() is None


def test_a_cut_keeps_the_speakers_level_so_a_sound_30_db_under_it_is_room_after_it() -> None:
    faint = np.concatenate([np.zeros(RATE // 2, dtype=np.float32), _tone(0.3, 0.5 * 10 ** (-35 / 20))])
    kept = SpeechEnds(RATE, HANGOVER)
    kept.add(_tone(0.5, 0.5))
    kept.restart(faint, keep_level=True)
    fresh = SpeechEnds(RATE, HANGOVER)
    fresh.add(_tone(0.5, 0.5))
    fresh.restart(faint, keep_level=False)
    assert (kept.heard_speech(), fresh.heard_speech()) == (False, True)
    assert fresh.samples == faint.size


def test_with_nothing_after_the_speech_the_cut_is_the_last_sample() -> None:
    ends = SpeechEnds(RATE, HANGOVER)
    ends.add(WORD[:12800])
    assert ends.end() == 12800


def test_a_sound_of_50_ms_in_the_room_is_no_speech_that_ended() -> None:
    ends = SpeechEnds(RATE, HANGOVER)
    ends.add(np.concatenate([_room(0.5), _tone(0.05, 0.5), _room(1.0, seed=2)]))
    assert not ends.heard_speech()
    assert ends.heard_end() is None
