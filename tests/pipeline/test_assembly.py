from typing import List

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fixtures.strategies import audio, split, split_points
from speech_event.pipeline.assembly import NonSpeech, UtteranceAssembler, quiet_cut, search_samples

RATE = 1000  # a small rate keeps examples small; the logic is rate-independent
MAX_SECONDS = 2.0
LIMIT = int(MAX_SECONDS * RATE)


def assemble(bursts: List[List[np.ndarray]]) -> List[np.ndarray]:
    """Feed bursts of blocks; a pause closes each burst."""
    assembler = UtteranceAssembler(RATE, MAX_SECONDS)
    utterances: List[np.ndarray] = []
    for blocks in bursts:
        for block in blocks:
            utterances.extend(assembler.add(block))
        closed = assembler.close()
        if closed is not None:
            utterances.append(closed)
    return utterances


bursts_of_audio = st.lists(audio(max_samples=3 * LIMIT), min_size=1, max_size=4)


@settings(max_examples=60)
@given(data=st.data(), bursts=bursts_of_audio)
def test_every_sample_lands_in_exactly_one_utterance_in_order(
    data: st.DataObject, bursts: List[np.ndarray]
) -> None:
    blocks = [split(burst, data.draw(split_points(burst.size))) for burst in bursts]
    utterances = assemble(blocks)
    assert np.array_equal(np.concatenate(utterances), np.concatenate(bursts))


@settings(max_examples=60)
@given(data=st.data(), bursts=bursts_of_audio)
def test_boundaries_do_not_depend_on_how_the_audio_was_cut_into_blocks(
    data: st.DataObject, bursts: List[np.ndarray]
) -> None:
    one_way = assemble([split(burst, data.draw(split_points(burst.size))) for burst in bursts])
    another_way = assemble([split(burst, data.draw(split_points(burst.size))) for burst in bursts])
    assert [u.size for u in one_way] == [u.size for u in another_way]
    assert all(np.array_equal(a, b) for a, b in zip(one_way, another_way))


@settings(max_examples=60)
@given(data=st.data(), burst=audio(max_samples=5 * LIMIT))
def test_an_utterance_cut_for_length_is_within_the_search_window_below_the_limit(
    data: st.DataObject, burst: np.ndarray
) -> None:
    utterances = assemble([split(burst, data.draw(split_points(burst.size)))])
    search = search_samples(LIMIT, RATE)
    for utterance in utterances[:-1]:  # all but the last were cut for length
        assert LIMIT - search <= utterance.size <= LIMIT
    assert utterances[-1].size <= LIMIT


def _loud_with_pauses(*pauses: "tuple[int, int]") -> np.ndarray:
    rng = np.random.default_rng(0)
    loud = rng.uniform(-0.5, 0.5, 3 * LIMIT).astype(np.float32)
    for start, stop in pauses:
        loud[start:stop] = 0.001 * rng.standard_normal(stop - start)
    return loud


def test_the_longest_pause_wins_over_a_later_shorter_one() -> None:
    # search: the last 30 % of the 2000-sample limit, 1400 to 2000
    assert quiet_cut(_loud_with_pauses((1450, 1650), (1900, 1950)), LIMIT, RATE) == 1550


def test_of_equally_long_pauses_the_cut_falls_in_the_last_before_the_limit() -> None:
    assert quiet_cut(_loud_with_pauses((1450, 1550), (1800, 1900)), LIMIT, RATE) == 1850


def test_a_short_dip_inside_a_word_loses_to_a_pause_even_if_the_dip_is_quieter() -> None:
    audio = _loud_with_pauses((1500, 1600))
    audio[1800:1830] = 0.0  # a 30 ms closure inside a word: quieter, but short
    assert 1500 <= quiet_cut(audio, LIMIT, RATE) < 1600


def _square(size: int, *levels: "tuple[int, int, float]") -> np.ndarray:
    """A +-0.5 square wave, with (start, stop, amplitude) stretches at other levels: exact energies."""
    amplitude = np.full(size, 0.5)
    for start, stop, level in levels:
        amplitude[start:stop] = level
    return (amplitude * np.where(np.arange(size) % 2, 1.0, -1.0)).astype(np.float32)


@pytest.mark.parametrize(
    ("second_half", "cut"),
    [
        (0.15, 1550),  # 3.5 dB above the first half: one pause, 1450 to 1650
        (0.3, 1500),  # 9.5 dB above: only the first half is quiet
    ],
)
def test_quiet_is_within_6_db_of_the_quietest_window_even_when_not_20_db_below_speech(
    second_half: float, cut: int
) -> None:
    # the pause, 14 dB and less below the speech, is a room's hum, not silence
    audio = _square(3 * LIMIT, (1450, 1550, 0.1), (1550, 1650, second_half))
    assert quiet_cut(audio, LIMIT, RATE) == cut


def test_digital_silence_is_quiet_even_when_it_is_most_of_the_search() -> None:
    audio = _loud_with_pauses()
    audio[1500:2400] = 0.0  # the windows' median energy is 0 too
    assert quiet_cut(audio, LIMIT, RATE) == 1750


@pytest.mark.parametrize("rate", [RATE, 16000])
def test_at_every_limit_the_cut_is_within_the_search_below_the_limit(rate: int) -> None:
    # every limit, so also those where the search ends exactly one window before the limit
    samples = np.resize(_loud_with_pauses((1450, 1650)), 3 * LIMIT + 1)
    for limit in range(1, 3 * LIMIT + 1):
        assert limit - search_samples(limit, rate) <= quiet_cut(samples, limit, rate) <= limit, limit


def test_a_limit_shorter_than_a_20_ms_window_is_cut_exactly_at_the_limit() -> None:
    assembler = UtteranceAssembler(RATE, 0.05)  # 50 samples; the search, 15, holds no window
    utterances = assembler.add(_loud_with_pauses()[:120])
    assert [utterance.size for utterance in utterances] == [50, 50]
    assert assembler.pending_samples == 20


def _vad_silent_from(seconds: float) -> NonSpeech:
    def non_speech(samples: np.ndarray, rate: int, first: int, hop: int) -> np.ndarray:
        hops = (samples.size - first) // hop
        return (np.arange(hops) * hop + first) / rate >= seconds

    return non_speech


def test_the_vad_decides_what_is_quiet_when_it_is_given() -> None:
    audio = _loud_with_pauses((1450, 1650))
    assert quiet_cut(audio, LIMIT, RATE, _vad_silent_from(1.9)) == 1950


def test_when_the_vad_hears_speech_throughout_the_energy_decides() -> None:
    audio = _loud_with_pauses((1450, 1650))
    assert quiet_cut(audio, LIMIT, RATE, _vad_silent_from(10.0)) == 1550


def test_the_assembler_cuts_where_its_vad_hears_no_speech() -> None:
    assembler = UtteranceAssembler(RATE, MAX_SECONDS, _vad_silent_from(1.9))
    utterances = assembler.add(_loud_with_pauses((1450, 1650))[: LIMIT + 100])
    assert [utterance.size for utterance in utterances] == [1950]
    assert assembler.pending_samples == 150


def test_an_utterance_that_reaches_the_limit_exactly_is_cut_at_once() -> None:
    audio = _loud_with_pauses((1450, 1650))[:LIMIT]
    assembler = UtteranceAssembler(RATE, MAX_SECONDS)
    utterances = assembler.add(audio)
    assert [utterance.size for utterance in utterances] == [1550]
    assert assembler.pending_samples == 450
    rest = assembler.close()
    assert rest is not None
    assert np.array_equal(rest, audio[1550:])


def test_close_on_nothing_collected_is_none() -> None:
    assembler = UtteranceAssembler(RATE, MAX_SECONDS)
    assert assembler.close() is None
    assert assembler.add(np.zeros(10, dtype=np.float32)) == []
    assert assembler.pending_samples == 10


def test_close_ends_the_utterance_so_nothing_is_pending_after_it() -> None:
    assembler = UtteranceAssembler(RATE, MAX_SECONDS)
    assembler.add(np.full(10, 0.25, dtype=np.float32))
    closed = assembler.close()
    assert closed is not None
    assert closed.tolist() == [0.25] * 10
    assert assembler.pending_samples == 0
    assert assembler.close() is None


def test_peek_shows_the_utterance_so_far_and_close_then_gives_the_same_samples() -> None:
    assembler = UtteranceAssembler(RATE, MAX_SECONDS)
    assembler.add(np.full(3, 0.25, dtype=np.float32))
    assembler.add(np.full(2, -0.5, dtype=np.float32))
    assert assembler.peek().tolist() == [0.25, 0.25, 0.25, -0.5, -0.5]
    assert assembler.pending_samples == 5
    closed = assembler.close()
    assert closed is not None
    assert closed.tolist() == [0.25, 0.25, 0.25, -0.5, -0.5]
