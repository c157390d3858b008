"""The driver's speech gate (issue 9, item 2), against a plain statement of what it must publish."""

from typing import List

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from fixtures.audio import noise
from fixtures.strategies import split, split_points
from fixtures.tts import speak_tts
from harness.driver import DriverConfig, gate_settings
from harness.gate import GateSettings, Piece, SpeechGate
from harness.vad_gate import VadGate

THRESHOLD = 0.5


@st.composite
def quiet_with_spikes(draw: st.DrawFn) -> np.ndarray:
    """Noise below the threshold with a few samples at or above it (the threshold itself included)."""
    size = draw(st.integers(0, 1500))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    audio = (rng.uniform(-1.0, 1.0, size) * THRESHOLD * 0.99).astype(np.float32)
    if size:
        for at in draw(st.lists(st.integers(0, size - 1), max_size=6)):
            audio[at] = draw(st.sampled_from([THRESHOLD, -THRESHOLD, 1.0, -0.75]))
    return audio


settings_strategy = st.builds(
    GateSettings, chunk_size=st.integers(1, 64), threshold=st.just(THRESHOLD), buffer=st.integers(0, 300)
)


def expected_indices(audio: np.ndarray, settings: GateSettings) -> np.ndarray:
    """Every chunk with a sample at or above the threshold, widened by the buffer on both sides
    and clipped to the stream: the sample indices to publish, in order, each once."""
    published = np.zeros(audio.size, dtype=bool)
    size = settings.chunk_size
    for start in range(0, audio.size, size):
        if np.max(np.abs(audio[start : start + size])) >= settings.threshold:
            low = max(0, start - settings.buffer)
            published[low : min(audio.size, start + size + settings.buffer)] = True
    return np.flatnonzero(published)


def gated(blocks: List[np.ndarray], settings: GateSettings) -> List[Piece]:
    gate = SpeechGate(settings)
    pieces: List[Piece] = []
    for block in blocks:
        pieces += gate.feed(block)
    return pieces + gate.finish()


def indices_of(pieces: List[Piece]) -> np.ndarray:
    return np.concatenate(
        [np.arange(start, start + piece.size) for start, piece in pieces] or [np.zeros(0, int)]
    )


@given(quiet_with_spikes().flatmap(lambda a: st.tuples(st.just(a), split_points(a.size))), settings_strategy)
def test_the_published_samples_are_exactly_the_padded_speech_regions_in_order(
    audio_and_points: "tuple[np.ndarray, List[int]]", settings: GateSettings
) -> None:
    audio, points = audio_and_points
    pieces = gated(split(audio, points), settings)
    indices = indices_of(pieces)
    assert np.array_equal(indices, expected_indices(audio, settings))
    published = np.concatenate([piece for _, piece in pieces] or [np.zeros(0, np.float32)])
    assert np.array_equal(published, audio[indices])  # the input's own samples, untouched


@given(quiet_with_spikes(), st.data(), settings_strategy)
def test_the_result_does_not_depend_on_how_the_input_was_cut(
    audio: np.ndarray, data: st.DataObject, settings: GateSettings
) -> None:
    one = gated(split(audio, data.draw(split_points(audio.size))), settings)
    other = gated(split(audio, data.draw(split_points(audio.size))), settings)
    assert np.array_equal(indices_of(one), indices_of(other))


@given(quiet_with_spikes(), settings_strategy)
def test_every_chunk_with_a_sample_at_the_threshold_is_published_whole(
    audio: np.ndarray, settings: GateSettings
) -> None:
    published = set(indices_of(gated([audio], settings)).tolist())
    for at in np.flatnonzero(np.abs(audio) >= THRESHOLD).tolist():
        chunk = at - at % settings.chunk_size
        assert set(range(chunk, min(audio.size, chunk + settings.chunk_size))) <= published


@given(st.integers(0, 5000), settings_strategy)
def test_silence_publishes_nothing(size: int, settings: GateSettings) -> None:
    assert gated([np.full(size, THRESHOLD * 0.999, dtype=np.float32)], settings) == []


def test_one_word_is_padded_by_exactly_the_buffer_and_close_words_merge() -> None:
    settings = GateSettings(chunk_size=100, threshold=THRESHOLD, buffer=250)
    audio = np.zeros(3000, dtype=np.float32)
    audio[1050] = 1.0  # chunk 1000..1100
    assert indices_of(gated([audio], settings)).tolist() == list(range(750, 1350))
    audio[1650] = 1.0  # chunk 1600..1700: 500 samples later, within two buffers: one region
    assert indices_of(gated([audio], settings)).tolist() == list(range(750, 1950))
    audio[10] = 1.0  # at the start: the pre-roll is clipped to the stream
    assert indices_of(gated([audio], settings))[:3].tolist() == [0, 1, 2]


def test_with_silero_vad_loud_noise_is_not_speech_and_the_spoken_words_are() -> None:
    """A noisy room: the amplitude alone opens the gate for noise; with Silero VAD it opens only
    around the words (a loud chunk must also be speech to the VAD)."""
    rate = 48000
    rng = np.random.default_rng(3)
    loud_noise = noise(2 * rate, -12.0, rng)  # peaks far above the 0.1 threshold
    words = speak_tts("go to the kitchen", rate)
    audio = np.concatenate([loud_noise, words, loud_noise]).astype(np.float32)
    config = DriverConfig(utterance_time_buffer=4800)
    plain = indices_of(gated([audio], gate_settings(config)))
    assert plain[0] < rate // 10  # the noise opened the amplitude gate at once
    vad_gate = SpeechGate(gate_settings(config), VadGate.from_config(DriverConfig(vad_threshold=0.5)))
    published = indices_of(vad_gate.feed(audio) + vad_gate.finish())
    speech_start, speech_end = loud_noise.size, loud_noise.size + words.size
    assert published.size > 0
    # nothing from the first 1.5 s of noise alone, nothing later than 1.5 s after the words
    assert published[0] >= int(1.5 * rate) and published[-1] < speech_end + int(1.5 * rate)
    heard = np.intersect1d(published, np.arange(speech_start, speech_end)).size
    assert heard > 0.8 * words.size
