from typing import List

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from speech_event.pipeline.assembly import UtteranceAssembler, quiet_cut, search_samples
from tests.helpers.strategies import audio, split, split_points

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


def test_the_vad_decides_what_is_quiet_when_it_is_given() -> None:
    audio = _loud_with_pauses((1450, 1650))

    def non_speech(samples: np.ndarray, rate: int, first: int, hop: int) -> np.ndarray:
        hops = (samples.size - first) // hop
        return np.arange(hops) * hop + first >= 1900  # the VAD hears no speech from 1900 on

    assert quiet_cut(audio, LIMIT, RATE, non_speech) == 1950


def test_close_on_nothing_collected_is_none() -> None:
    assembler = UtteranceAssembler(RATE, MAX_SECONDS)
    assert assembler.close() is None
    assert assembler.add(np.zeros(10, dtype=np.float32)) == []
    assert assembler.pending_samples == 10
