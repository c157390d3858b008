"""pocketsphinx decodes each utterance as a fresh decoder would (issue 30): what it heard before, in
final texts or partial results, never changes a text or the ratio a grammar judges by.

Before, a decoder's feature extraction carried its noise estimate and cepstral mean from one
utterance to the next: the cards recordings scored up to 20 nats apart by the order they came in.
"""

from typing import List, Optional, Tuple

import numpy as np
import pytest

from fixtures import recordings
from speech_event.grammar import Grammar, load_grammar
from speech_event.ports import Transcript
from speech_event.recognizers.sphinx import SphinxRecognizer

Heard = Tuple[Transcript, Optional[float]]


def _heard(recognizer: SphinxRecognizer, audio: np.ndarray) -> Heard:
    return recognizer.transcribe(audio), recognizer.last_ratio


def _feed_partials(recognizer: SphinxRecognizer, grammar: Optional[Grammar], audio: np.ndarray) -> None:
    recognizer.begin_partial(grammar)
    for start in range(0, audio.size, 1600):
        recognizer.feed_partial(audio[start : start + 1600])


@pytest.mark.parametrize("mode", ["cards.gram", "language model"])
def test_recordings_decode_alike_in_either_order_with_partials_between(mode: str) -> None:
    """Each order's first recording meets a fresh decoder, so equal orders mean every recording
    decodes as on a fresh one (before, every card's ratio changed with the order)."""
    grammar = load_grammar(recordings.CARDS_GRAMMAR) if mode == "cards.gram" else None
    # With the language model, librivox 0870 after card 001 read 'but mr john guess...' for 'and ...'.
    said = [recordings.cards()[0], recordings.cards()[2], recordings.cards()[3]]
    if grammar is None:
        said = [recordings.cards()[0], recordings.librivox()[0]]
    audio = [recording.samples() for recording in said]

    forward = SphinxRecognizer(grammar)
    in_order = [_heard(forward, samples) for samples in audio]
    backward = SphinxRecognizer(grammar)
    in_reverse: List[Heard] = []
    for samples in reversed(audio):
        in_reverse.insert(0, _heard(backward, samples))
        _feed_partials(backward, grammar, samples[::-1][:16000])  # other audio on the partial decoder
    assert in_order == in_reverse
    if grammar is not None:  # exactly the cards said, each judged
        assert [(transcript.text, ratio is not None) for transcript, ratio in in_order] == [
            (recording.text, True) for recording in said
        ]


def test_an_empty_piece_fed_as_a_partial_is_taken_as_no_audio() -> None:
    """A stream resampler's first piece can be empty (it holds samples back for its filter):
    pocketsphinx raised IndexError on it, and the rest of that feed was lost."""
    grammar = load_grammar(recordings.CARDS_GRAMMAR)
    audio = recordings.cards()[2].samples()
    recognizer = SphinxRecognizer(grammar)

    def partials(pieces: List[np.ndarray]) -> List[str]:
        recognizer.begin_partial(grammar)
        return [recognizer.feed_partial(piece).text for piece in pieces]

    halves = [audio[: audio.size // 2], audio[audio.size // 2 :]]
    assert partials([np.zeros(0, np.float32), *halves]) == ["", *partials(halves)]
