"""Phrase scoring along the forms' prefix tree (speech_event/recognizers/whisper/phrase_tree.py):
exact where a decision needs it (the same as forced.score_phrases, each form in one call of its own),
bounds below ``least`` and the best elsewhere, and each shared stretch run once."""

from typing import Dict, List

import numpy as np
import pytest

from fixtures.audio import speak_tones
from fixtures.recorded_decoding import RecordedDecoding
from fixtures.whisper_tones_model import MANIFEST, whisper_tones_model_directory
from speech_event.recognizers.whisper.features import whisper_log_mel
from speech_event.recognizers.whisper.forced import score_phrases
from speech_event.recognizers.whisper.manifest import load_tokens
from speech_event.recognizers.whisper.model import DecoderSession, WhisperModel
from speech_event.recognizers.whisper.phrase_tree import score_phrases_that_decide
from speech_event.recognizers.whisper.tokenizer import WhisperTokenizer

PROMPT = MANIFEST.prompt("english")
TEXTS = [
    " go left",
    " go lefts",
    " go lift",
    " go",
    " stop",
    " stop stop",
    " a",
    " go to the kitchen",
    " left",
]
# a form run in stretches and in one call agree to float32's rounding
CLOSE = 1e-5


@pytest.fixture(scope="module")
def tones_model() -> WhisperModel:
    return WhisperModel(whisper_tones_model_directory())


def _tokens(text: str) -> List[int]:
    return WhisperTokenizer(load_tokens(whisper_tones_model_directory() / "tokens.txt"), MANIFEST.eot).encode(
        text
    )


def _session(model: WhisperModel, said: str, calls: List[List[int]]) -> RecordedDecoding:
    cross: Dict[str, np.ndarray] = model.encode(whisper_log_mel(speak_tones(said, 16000), MANIFEST.mel_bands))
    return RecordedDecoding(DecoderSession(model, cross), calls)


@pytest.mark.parametrize("least", [-8.0, 0.0, -20.0, -np.inf])
def test_what_can_decide_is_exact_and_every_other_form_bounded_under_least_and_the_best(
    tones_model: WhisperModel, least: float
) -> None:
    sequences = [_tokens(text) for text in TEXTS]
    calls: List[List[int]] = []
    session = _session(tones_model, "go left", calls)
    prompted = session(PROMPT)
    exact = score_phrases(session.fork(), PROMPT, sequences, MANIFEST, prompted)
    always = [TEXTS.index(" a")]  # scored whatever its score: the free text's phrase, for its evidence
    scores = score_phrases_that_decide(session, PROMPT, sequences, MANIFEST, prompted, least, always)
    best = int(np.argmax(exact))
    for index, (score, truth) in enumerate(zip(scores, exact)):
        if truth >= least or index == best or index in always:
            assert score == truth, TEXTS[index]  # as one call of its own scores it
        else:  # an upper bound of its score, below least and the best's score
            assert truth - CLOSE <= score < least and score <= exact[best] + CLOSE, TEXTS[index]
    if least == 0.0:  # none reaches it: the best, the one always scored, and what might beat the best
        assert sum(score != pytest.approx(truth, abs=CLOSE) for score, truth in zip(scores, exact)) > 0


def test_each_shared_stretch_is_run_once_and_a_stretch_with_one_way_on_in_one_call(
    tones_model: WhisperModel,
) -> None:
    sequences = [_tokens(text) for text in TEXTS]
    calls: List[List[int]] = []
    session = _session(tones_model, "go left", calls)
    prompted = session(PROMPT)
    calls.clear()
    # no sequence reaches 0: only the best needs its score, and what may beat it
    scores = score_phrases_that_decide(session, PROMPT, sequences, MANIFEST, prompted, 0.0)
    go = _tokens(" go")
    assert calls.count(go) == 1  # the prefix of five forms, where they branch
    assert len(calls) < len(sequences) and sum(map(len, calls)) < sum(map(len, sequences))
    exact = score_phrases(session.fork(), PROMPT, sequences, MANIFEST, prompted)
    assert scores[TEXTS.index(" go left")] == max(exact)


def test_a_branch_that_cannot_decide_costs_no_call_and_an_empty_form_is_ruled_out(
    tones_model: WhisperModel,
) -> None:
    sequences = [_tokens(" go left"), _tokens(" stop stop"), []]
    calls: List[List[int]] = []
    session = _session(tones_model, "go left", calls)
    prompted = session(PROMPT)
    exact = score_phrases(session.fork(), PROMPT, sequences, MANIFEST, prompted)
    calls.clear()
    # least at the best form's score: " stop"'s first token alone is less probable
    scores = score_phrases_that_decide(session, PROMPT, sequences, MANIFEST, prompted, exact[0])
    assert calls == [sequences[0]]
    assert scores[0] == pytest.approx(exact[0], abs=CLOSE) and exact[1] < scores[1] < exact[0]
    assert scores[2] == -np.inf  # eot first, which Whisper's rules rule out
    with pytest.raises(ValueError, match="exceed the decoder's"):
        score_phrases_that_decide(session, PROMPT, [[1] * MANIFEST.text_context], MANIFEST, prompted, 0.0)
