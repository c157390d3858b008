"""Teacher-forced phrase scores (speech_event/recognizers/whisper/forced.py): exact against greedy
decoding's own score and against a brute-force scorer, on the tones Whisper model and on a decoder
whose logits depend on every token before; the phrases' surface forms and tokens."""

import dataclasses
import shutil
from pathlib import Path
from typing import Callable, Dict, List, Sequence, Tuple

import numpy as np
import onnx
import pytest
from onnx import helper

from fixtures.audio import speak_tones
from fixtures.transducer_model import tensor
from fixtures.whisper_tones_model import (
    MANIFEST,
    NO_SPEECH,
    PIECES,
    SOT,
    TIMESTAMP_BEGIN,
    VOCABULARY,
    WIDTH,
    decoder_model,
    whisper_tones_model_directory,
)
from speech_event.recognizers.whisper.features import whisper_log_mel
from speech_event.recognizers.whisper.forced import (
    UnheardScores,
    forced_log_likelihood,
    score_phrases,
)
from speech_event.recognizers.whisper.greedy import whisper_greedy
from speech_event.recognizers.whisper.manifest import load_tokens, text_of
from speech_event.recognizers.whisper.model import DECODER_FILE, DecoderSession, WhisperModel
from speech_event.recognizers.whisper.tokenizer import WhisperTokenizer

RATE = 16000
PROMPT = MANIFEST.prompt("english")
TOKENS = load_tokens(whisper_tones_model_directory() / "tokens.txt")


def _tokens(text: str) -> List[int]:
    return WhisperTokenizer(TOKENS, MANIFEST.eot).encode(text)


@pytest.fixture(scope="module")
def tones_model() -> WhisperModel:
    return WhisperModel(whisper_tones_model_directory())


def _cross(model: WhisperModel, text: str) -> Dict[str, np.ndarray]:
    return model.encode(whisper_log_mel(speak_tones(text, RATE), MANIFEST.mel_bands))


def _brute_force(model: WhisperModel, cross: Dict[str, np.ndarray], tokens: Sequence[int]) -> float:
    """log P(tokens, eot): the decoder fed one token at a time in a session of this sequence's own,
    each position's logits masked here (float64) and normalised by log-sum-exp."""
    session = DecoderSession(model, cross)
    rows = [session([token])[-1] for token in [*PROMPT, *tokens]][len(PROMPT) - 1 :]
    total = 0.0
    for position, (row, target) in enumerate(zip(rows, [*tokens, MANIFEST.eot])):
        masked = np.array(row, np.float64)
        masked[list(MANIFEST.suppress)] = -np.inf
        if position == 0:
            masked[list(MANIFEST.suppress_at_start)] = -np.inf
        total += masked[target] - (masked.max() + np.log(np.exp(masked - masked.max()).sum()))
    return total


@pytest.mark.parametrize("spoken", ["go left", "stop", "go to the kitchen"])
def test_the_greedy_texts_forced_score_is_its_greedy_score(tones_model: WhisperModel, spoken: str) -> None:
    cross = _cross(tones_model, spoken)
    result = whisper_greedy(DecoderSession(tones_model, cross), PROMPT, MANIFEST)
    assert text_of(result.tokens, TOKENS, TIMESTAMP_BEGIN) == f" {spoken}"  # ended on eot
    assert np.isfinite(result.score) and result.score < 0.0
    assert score_phrases(DecoderSession(tones_model, cross), PROMPT, [result.tokens], MANIFEST) == [
        pytest.approx(result.score, abs=1e-5)
    ]


def test_forcing_many_phrases_after_one_prompt_is_the_brute_force_score(tones_model: WhisperModel) -> None:
    cross = _cross(tones_model, "go left")
    sequences = [_tokens(text) for text in (" go left", " go lefts", " go lift", " go", " stop", " a")]
    sequences.append([TIMESTAMP_BEGIN, *_tokens(" go")])  # a timestamp is no text, yet a token
    scores = score_phrases(DecoderSession(tones_model, cross), PROMPT, sequences, MANIFEST)
    assert scores == [
        pytest.approx(_brute_force(tones_model, cross, tokens), abs=1e-5) for tokens in sequences
    ]


def test_unheard_scores_are_the_brute_force_scores_against_silence_encoded_once(
    tones_model: WhisperModel, monkeypatch: pytest.MonkeyPatch
) -> None:
    encoded: List[int] = []
    encode = WhisperModel.encode

    def counted(model: WhisperModel, mel: np.ndarray, run: object = None) -> Dict[str, np.ndarray]:
        encoded.append(mel.shape[-1])
        return encode(model, mel)

    monkeypatch.setattr(WhisperModel, "encode", counted)
    unheard = UnheardScores(tones_model, PROMPT, MANIFEST)
    assert unheard([]) == [] and encoded == []  # nothing to score: nothing encoded
    sequences = [_tokens(text) for text in (" go left", " stop")]
    silence = tones_model.encode(whisper_log_mel(np.zeros(0, np.float32), MANIFEST.mel_bands))
    expected = [pytest.approx(_brute_force(tones_model, silence, tokens), abs=1e-5) for tokens in sequences]
    encoded.clear()
    assert unheard(sequences) == expected
    assert unheard(sequences[::-1]) == expected[::-1]
    assert encoded == [3000]  # one 30 s window, at the first call


def _history_decoder(seed: int) -> onnx.ModelProto:
    """A decoder.onnx whose logits at a position depend on every token up to it, through the cache
    it carries, and on the audio: tanh(sum of the embeddings so far + the mean audio row) @ W."""
    rng = np.random.default_rng(seed)
    node = helper.make_node
    nodes = [
        node("Gather", ["embedding", "tokens"], ["embedded"]),  # [1, n, W]
        node("Unsqueeze", ["embedded", "zero_one_i"], ["entries"]),  # [1, 1, 1, n, W]
        node("Concat", ["self_k", "entries"], ["new_self_k"], axis=3),
        node("Concat", ["self_v", "entries"], ["new_self_v"], axis=3),
        node("CumSum", ["new_self_k", "positions_axis"], ["so_far"]),
        node("Shape", ["self_k"], ["cache_shape"]),
        node("Slice", ["cache_shape", "three_i", "four_i"], ["past"]),
        node("Slice", ["so_far", "past", "end_i", "three_i"], ["new_so_far"]),  # [1, 1, 1, n, W]
        node("Squeeze", ["new_so_far", "zero_one_i"], ["history"]),  # [1, n, W]
        node("ReduceMean", ["cross_v_0"], ["audio"], axes=[1, 2], keepdims=0),  # [1, W]
        node("Add", ["history", "audio"], ["state"]),
        node("Tanh", ["state"], ["squashed"]),
        node("MatMul", ["squashed", "projection"], ["logits"]),  # [1, n, V]
    ]
    initializers = [
        tensor("embedding", rng.normal(0.0, 0.3, (VOCABULARY, WIDTH)).astype(np.float32)),
        tensor("projection", rng.normal(0.0, 1.0, (WIDTH, VOCABULARY)).astype(np.float32)),
        tensor("zero_one_i", np.array([0, 1], np.int64)),
        tensor("three_i", np.array([3], np.int64)),
        tensor("four_i", np.array([4], np.int64)),
        tensor("end_i", np.array([np.iinfo(np.int64).max], np.int64)),
        tensor("positions_axis", np.array(3, np.int64)),
    ]
    return decoder_model("history_decoder", nodes, initializers)


def test_forcing_is_exact_where_the_logits_depend_on_every_token_before(tmp_path: Path) -> None:
    directory = shutil.copytree(whisper_tones_model_directory(), tmp_path / "model")
    onnx.save(_history_decoder(seed=3), str(directory / DECODER_FILE))
    model = WhisperModel(directory)
    cross = _cross(model, "go left")
    rng = np.random.default_rng(4)
    sequences = [[int(token) for token in rng.integers(0, len(PIECES), size)] for size in (1, 2, 5, 9, 5)]
    sequences.append(sequences[2][:3])  # a prefix of an earlier sequence, scored after it
    scores = score_phrases(DecoderSession(model, cross), PROMPT, sequences, MANIFEST)
    assert len(set(scores)) == len(scores) and all(np.isfinite(scores))
    assert scores == [pytest.approx(_brute_force(model, cross, tokens), abs=1e-5) for tokens in sequences]


def test_unheard_scores_are_exact_where_the_logits_depend_on_every_token_before(tmp_path: Path) -> None:
    """Each sequence scored from the silence's prompt alone, whatever was scored before it: a
    decoder whose logits follow the whole history would show a shared cache written into."""
    directory = shutil.copytree(whisper_tones_model_directory(), tmp_path / "model")
    onnx.save(_history_decoder(seed=5), str(directory / DECODER_FILE))
    model = WhisperModel(directory)
    silence = model.encode(whisper_log_mel(np.zeros(RATE, np.float32), MANIFEST.mel_bands))
    rng = np.random.default_rng(6)
    sequences = [[int(token) for token in rng.integers(0, len(PIECES), size)] for size in (3, 1, 6, 3)]
    unheard = UnheardScores(model, PROMPT, MANIFEST)
    scores = unheard(sequences) + unheard(sequences[::-1])
    assert len(set(scores)) == len(sequences) and all(np.isfinite(scores))
    expected = [pytest.approx(_brute_force(model, silence, tokens), abs=1e-5) for tokens in sequences]
    assert scores == expected + expected[::-1]


def test_the_spoken_phrase_outscores_its_near_misses(tones_model: WhisperModel) -> None:
    texts = [" go left", " go lefts", " go lift", " go"]
    spoken, *misses = score_phrases(
        DecoderSession(tones_model, _cross(tones_model, "go left")),
        PROMPT,
        [_tokens(t) for t in texts],
        MANIFEST,
    )
    assert all(spoken > miss for miss in misses), (spoken, misses)


def test_a_token_whispers_rules_rule_out_scores_minus_infinity(tones_model: WhisperModel) -> None:
    cross = _cross(tones_model, "go left")
    go, left = _tokens(" go"), _tokens(" left")
    scores = score_phrases(
        DecoderSession(tones_model, cross), PROMPT, [[*go, NO_SPEECH, *left], [SOT, *go], []], MANIFEST
    )
    assert scores == [-np.inf, -np.inf, -np.inf]  # suppressed anywhere; eot at the first position


# For the pure functions, 4 tokens: 0 " " and 1 text, 2 eot, 3 suppressed.
SMALL = dataclasses.replace(MANIFEST, vocabulary_size=4, eot=2, suppress=(3,), suppress_at_start=(0, 2))


def _row(values: Tuple[float, ...]) -> np.ndarray:
    return np.array(values, np.float32)


def test_masking_comes_before_the_log_softmax() -> None:
    # token 3 suppressed everywhere with the highest logit, 0 and eot at the first position
    logits = np.stack([_row((5.0, 1.0, 9.0, 50.0)), _row((1.0, 2.0, 3.0, 50.0))])
    first = 1.0 - 1.0  # only token 1 is left at the first position: probability 1
    then_eot = 3.0 - np.log(np.exp(1.0) + np.exp(2.0) + np.exp(3.0))
    assert forced_log_likelihood(logits, [1], SMALL) == pytest.approx(first + then_eot, abs=1e-12)
    assert forced_log_likelihood(logits, [0], SMALL) == -np.inf
    assert forced_log_likelihood(logits[:1], [], SMALL) == -np.inf  # eot at the first position
    with pytest.raises(ValueError):
        forced_log_likelihood(logits, [1, 1], SMALL)


def _repeating(first: Tuple[float, ...], then: Tuple[float, ...]) -> Callable[[Sequence[int]], np.ndarray]:
    """A decoder whose last prompt position gives ``first`` and every position after it ``then``."""

    def step(tokens: Sequence[int]) -> np.ndarray:
        return np.stack([_row(first)] * len(tokens) if len(tokens) > 1 else [_row(then)])

    return step


def test_greedy_scores_what_it_samples_and_the_eot_it_ends_on() -> None:
    manifest = dataclasses.replace(SMALL, no_speech=None, text_context=8)  # sample_len 4
    # first step: 0 and eot ruled out, 1 alone is left (probability 1); then eot is best
    ended = whisper_greedy(_repeating((4.0, 1.0, 2.0, 50.0), (1.0, 1.0, 4.0, 50.0)), [SOT, SOT], manifest)
    assert ended.tokens == [1]
    assert ended.score == pytest.approx(4.0 - np.log(2 * np.exp(1.0) + np.exp(4.0)), abs=1e-12)
    # then 0 is best at every step, until sample_len: no eot term
    cut = whisper_greedy(_repeating((4.0, 1.0, 2.0, 50.0), (4.0, 1.0, 2.0, 50.0)), [SOT, SOT], manifest)
    assert cut.tokens == [1, 0, 0, 0]
    then_zero = 4.0 - np.log(np.exp(4.0) + np.exp(1.0) + np.exp(2.0))
    assert cut.score == pytest.approx(3 * then_zero, abs=1e-12)
