"""Exact phrase scores: the CTC, RNN-T and TDT log-likelihoods against a brute-force sum over every
alignment, the decoder-joint lattice against step-by-step calls, the trie scorer against scoring
each sequence alone, and the vocabulary's spelling of text as token ids."""

import itertools
import math
from pathlib import Path
from typing import Any, Callable, Dict, List, Sequence, Tuple

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fixtures.audio import noise, speak_tones
from fixtures.tones_model import tones_tdt_model_directory
from fixtures.transducer_model import PIECES, build_random_ctc, build_random_transducer
from speech_event.errors import ModelError
from speech_event.pipeline.resample import resample
from speech_event.recognizers.nemo import phrase_scores
from speech_event.recognizers.nemo.ctc import ctc_greedy, ctc_log_likelihood
from speech_event.recognizers.nemo.features import features
from speech_event.recognizers.nemo.manifest import MANIFEST_FILE, load_manifest
from speech_event.recognizers.nemo.model import CtcModel, TransducerModel
from speech_event.recognizers.nemo.phrase_scores import rnnt_scores, tdt_scores
from speech_event.recognizers.nemo.recognizer import VOCABULARY_FILE, padded_as_nemo_does
from speech_event.recognizers.nemo.rnnt import (
    blank_and_token_log_probabilities,
    rnnt_forward,
    rnnt_greedy,
    rnnt_log_likelihood,
)
from speech_event.recognizers.nemo.tdt import tdt_greedy, tdt_log_likelihood
from speech_event.recognizers.nemo.vocabulary import Vocabulary, load_vocabulary
from speech_event.recognizers.onnx.hypothesis import log_softmax

TDT_DURATIONS = (0, 1, 2)
VOCABULARY = Vocabulary(PIECES)
BLANK = VOCABULARY.blank


def _log_sum(scores: List[float]) -> float:
    """log(sum(exp(scores))), -inf for no scores: the brute force's own, apart from numpy's."""
    top = max(scores, default=-math.inf)
    if top == -math.inf:
        return -math.inf
    return top + math.log(sum(math.exp(score - top) for score in scores))


def _assert_same(found: float, expected: float) -> None:
    if math.isinf(expected):
        assert found == expected
    else:
        assert abs(found - expected) <= 1e-9


def _rows(logits: np.ndarray) -> np.ndarray:
    """Each row log-softmaxed one at a time, as the greedy decoders do."""
    return np.array([log_softmax(row) for row in logits.reshape(-1, logits.shape[-1])]).reshape(logits.shape)


def _ctc_brute_force(logits: np.ndarray, tokens: Sequence[int], blank: int) -> float:
    """Every labelling of the frames that merges repeats and drops blanks to ``tokens``."""
    log_probabilities = _rows(logits)
    scores = []
    for labels in itertools.product(range(logits.shape[1]), repeat=len(logits)):
        merged = [k for i, k in enumerate(labels) if k != blank and (i == 0 or labels[i - 1] != k)]
        if merged == list(tokens):
            scores.append(sum(log_probabilities[t, k] for t, k in enumerate(labels)))
    return _log_sum(scores)


def _rnnt_brute_force(lattice: np.ndarray, tokens: Sequence[int], blank: int) -> float:
    """Every order of the U tokens and T' blanks that ends with a blank."""
    log_probabilities = _rows(lattice)
    frames, moves = len(lattice), len(lattice) + len(tokens)
    scores = []
    for emissions in itertools.combinations(range(moves - 1), len(tokens)):
        t = u = 0
        score = 0.0
        for move in range(moves):
            if move in emissions:
                score += log_probabilities[t, u, tokens[u]]
                u += 1
            else:
                score += log_probabilities[t, u, blank]
                t += 1
        assert (t, u) == (frames, len(tokens))
        scores.append(score)
    return _log_sum(scores)


def _tdt_brute_force(
    lattice: np.ndarray, tokens: Sequence[int], blank: int, durations: Sequence[int]
) -> float:
    """Every sequence of (token or blank, duration) moves, each from a frame before T', that ends
    with a blank landing exactly on T' with every token emitted; a blank never has duration 0."""
    split = lattice.shape[-1] - len(durations)
    token_lp, duration_lp = _rows(lattice[..., :split]), _rows(lattice[..., split:])
    frames = len(lattice)
    moves = [(True, i) for i in range(len(durations))]
    moves += [(False, i) for i, d in enumerate(durations) if d > 0]
    scores = []
    for length in range(1, frames + len(tokens) + 1):  # each blank moves on a frame at least
        for path in itertools.product(moves, repeat=length):
            t = u = 0
            score, possible = 0.0, True
            for emits, i in path:
                if t >= frames or (emits and u == len(tokens)):
                    possible = False
                    break
                score += token_lp[t, u, tokens[u] if emits else blank] + duration_lp[t, u, i]
                t, u = t + durations[i], u + int(emits)
            if possible and not path[-1][0] and (t, u) == (frames, len(tokens)):
                scores.append(score)
    return _log_sum(scores)


def _one_per_frame_brute_force(lattice: np.ndarray, tokens: Sequence[int], blank: int) -> float:
    """max_symbols_per_step = 1: at each frame the blank or the next token, either moving a frame
    on; every choice of the U frames that emit, ending on T' with all tokens emitted."""
    log_probabilities = _rows(lattice)
    scores = []
    for emitting in itertools.combinations(range(len(lattice)), len(tokens)):
        u, score = 0, 0.0
        for t in range(len(lattice)):
            if t in emitting:
                score += log_probabilities[t, u, tokens[u]]
                u += 1
            else:
                score += log_probabilities[t, u, blank]
        scores.append(score)
    return _log_sum(scores)


def _tdt_past_end_brute_force(
    lattice: np.ndarray, tokens: Sequence[int], blank: int, durations: Sequence[int]
) -> float:
    """Every sequence of (token or blank, duration) moves from frames before T' whose last move
    reaches or passes T' with every token emitted (where greedy decoding stops)."""
    split = lattice.shape[-1] - len(durations)
    token_lp, duration_lp = _rows(lattice[..., :split]), _rows(lattice[..., split:])
    frames = len(lattice)
    moves = [(True, i) for i in range(len(durations))]
    moves += [(False, i) for i, d in enumerate(durations) if d > 0]
    scores = []
    for length in range(1, frames + len(tokens) + 1):
        for path in itertools.product(moves, repeat=length):
            t = u = 0
            score, possible = 0.0, True
            for emits, i in path:
                if t >= frames or (emits and u == len(tokens)):
                    possible = False
                    break
                score += token_lp[t, u, tokens[u] if emits else blank] + duration_lp[t, u, i]
                t, u = t + durations[i], u + int(emits)
            if possible and t >= frames and u == len(tokens):
                scores.append(score)
    return _log_sum(scores)


def _random_case(
    seed: int, frames: int, length: int, tokens_with_blank: int, extra: int = 0
) -> Tuple[np.ndarray, List[int]]:
    """Logits [frames, length + 1, tokens_with_blank + extra] and ``length`` tokens (repeats likely)."""
    rng = np.random.default_rng(seed)
    tokens = [int(k) for k in rng.integers(0, tokens_with_blank - 1, size=length)]
    return 2.0 * rng.standard_normal((frames, length + 1, tokens_with_blank + extra)), tokens


SIZES = {
    "seed": st.integers(0, 2**32 - 1),
    "frames": st.integers(1, 4),
    "length": st.integers(0, 2),
    "tokens_with_blank": st.sampled_from([3, 4]),
}


@settings(max_examples=60, deadline=None)
@given(**SIZES)
def test_ctc_log_likelihood_is_the_sum_over_every_alignment(
    seed: int, frames: int, length: int, tokens_with_blank: int
) -> None:
    lattice, tokens = _random_case(seed, frames, length, tokens_with_blank)
    logits, blank = lattice[:, 0], tokens_with_blank - 1
    _assert_same(ctc_log_likelihood(logits, tokens, blank), _ctc_brute_force(logits, tokens, blank))


@settings(max_examples=60, deadline=None)
@given(**SIZES)
def test_rnnt_log_likelihood_is_the_sum_over_every_alignment(
    seed: int, frames: int, length: int, tokens_with_blank: int
) -> None:
    lattice, tokens = _random_case(seed, frames, length, tokens_with_blank)
    blank = tokens_with_blank - 1
    _assert_same(rnnt_log_likelihood(lattice, tokens, blank), _rnnt_brute_force(lattice, tokens, blank))


@settings(max_examples=60, deadline=None)
@given(**SIZES)
def test_one_token_a_frame_rnnt_is_the_sum_over_every_alignment_of_that_decoding(
    seed: int, frames: int, length: int, tokens_with_blank: int
) -> None:
    lattice, tokens = _random_case(seed, frames, length, tokens_with_blank)
    blank = tokens_with_blank - 1
    log_probabilities = log_softmax(lattice)
    found = rnnt_forward(
        *blank_and_token_log_probabilities(log_probabilities, tokens, blank), one_per_frame=True
    )
    _assert_same(found, _one_per_frame_brute_force(lattice, tokens, blank))


@settings(max_examples=60, deadline=None)
@given(durations=st.sampled_from([TDT_DURATIONS, (0, 2), (1, 2), (2, 3)]), **SIZES)
def test_tdt_to_where_greedy_stops_is_the_sum_over_every_such_alignment(
    seed: int, frames: int, length: int, tokens_with_blank: int, durations: Tuple[int, ...]
) -> None:
    lattice, tokens = _random_case(seed, frames, length, tokens_with_blank, len(durations))
    blank = tokens_with_blank - 1
    _assert_same(
        tdt_log_likelihood(lattice, tokens, blank, durations, past_end=True),
        _tdt_past_end_brute_force(lattice, tokens, blank, durations),
    )


@settings(max_examples=60, deadline=None)
@given(durations=st.sampled_from([TDT_DURATIONS, (0, 2), (1, 2), (0,), (2, 3)]), **SIZES)
def test_tdt_log_likelihood_is_the_sum_over_every_alignment(
    seed: int, frames: int, length: int, tokens_with_blank: int, durations: Tuple[int, ...]
) -> None:
    lattice, tokens = _random_case(seed, frames, length, tokens_with_blank, len(durations))
    blank = tokens_with_blank - 1
    _assert_same(
        tdt_log_likelihood(lattice, tokens, blank, durations),
        _tdt_brute_force(lattice, tokens, blank, durations),
    )


@pytest.mark.parametrize(
    ("score", "frames", "length"),
    [
        # too few frames: a repeated token needs a blank between (3 frames), two tokens 2 frames
        (lambda lattice, tokens: ctc_log_likelihood(lattice[:, 0], tokens, 2), 2, 2),
        (lambda lattice, tokens: ctc_log_likelihood(lattice[:, 0], tokens, 2), 1, 2),
        # blanks of 2 frames, tokens of 0 or 2: frame 3 is never landed on
        (lambda lattice, tokens: tdt_log_likelihood(lattice, tokens, 2, (0, 2)), 3, 1),
        # a blank never stays: with only duration 0 no path ends
        (lambda lattice, tokens: tdt_log_likelihood(lattice, tokens, 2, (0,)), 2, 0),
    ],
)
def test_impossible_sequences_have_log_likelihood_minus_infinity(
    score: Callable[[np.ndarray, List[int]], float], frames: int, length: int
) -> None:
    lattice = np.random.default_rng(0).standard_normal((frames, length + 1, 5))
    assert score(lattice, [1] * length) == -math.inf


def test_rnnt_log_likelihood_of_no_frames_is_minus_infinity() -> None:
    assert rnnt_log_likelihood(np.zeros((0, 1, 3)), [], 2) == -math.inf  # the last blank needs a frame


@pytest.fixture(scope="module")
def models(tmp_path_factory: pytest.TempPathFactory) -> Dict[str, Path]:
    directory = tmp_path_factory.mktemp("models")
    return {
        "rnnt": build_random_transducer(directory / "rnnt"),
        "tdt": build_random_transducer(directory / "tdt", durations=TDT_DURATIONS),
        "ctc": build_random_ctc(directory / "ctc"),
    }


def _audio(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.concatenate([noise(16000, -30.0, rng), resample(speak_tones("muraho", 48000), 48000, 16000)])


def _encoded(directory: Path, seed: int) -> Tuple[TransducerModel, np.ndarray]:
    model = TransducerModel(directory)
    feature_settings = load_manifest(directory / MANIFEST_FILE).features
    return model, model.encode(features(padded_as_nemo_does(_audio(seed), 16000), feature_settings))


def _greedy_moves(
    model: TransducerModel, frames: np.ndarray, durations: Sequence[int]
) -> Tuple[List[int], List[Tuple[int, int, int]]]:
    """Greedy decoding's tokens, and its path: (frame, token, duration index) per decoder-joint step.
    The frame's index rides along as a last column, so that each step says where it is."""
    moves: List[Tuple[int, int, int]] = []

    def step(frame: np.ndarray, last: int, state: Any) -> Tuple[np.ndarray, Any]:
        logits, after = model.step(frame[:-1], last, state)
        split = len(logits) - len(durations)
        duration = int(np.argmax(logits[split:])) if durations else 0
        moves.append((int(frame[-1]), int(np.argmax(logits[:split])), duration))
        return logits, after

    indexed = np.hstack([frames, np.arange(len(frames), dtype=frames.dtype)[:, None]])
    state = model.initial_state()
    if durations:
        found = tdt_greedy(indexed, step, state, BLANK, durations, max_symbols=10)
    else:
        found = rnnt_greedy(indexed, step, state, BLANK, max_symbols=10)
    return found.tokens, moves


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_greedy_rnnt_tokens_are_at_least_as_likely_as_the_greedy_path(
    models: Dict[str, Path], seed: int
) -> None:
    model, frames = _encoded(models["rnnt"], seed)
    tokens, moves = _greedy_moves(model, frames, ())
    lattice = model.lattice(frames, tokens, BLANK)
    log_probabilities = log_softmax(lattice)
    # greedy's path on the lattice; a frame it left at the max_symbols cap (this model reaches it) is
    # closed by the blank it did not take there, so that the path is an alignment: a term of the sum
    t = u = 0
    path_score = 0.0
    for frame, token, _ in moves:
        if frame > t:
            path_score += log_probabilities[t, u, BLANK]
            t += 1
        assert frame == t
        path_score += log_probabilities[t, u, token]
        t, u = (t + 1, u) if token == BLANK else (t, u + 1)
    if t < len(frames):
        path_score += log_probabilities[t, u, BLANK]
        t += 1
    assert (t, u) == (len(frames), len(tokens))
    assert len(tokens) > 0
    assert path_score <= rnnt_log_likelihood(lattice, tokens, BLANK) < 0.0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_greedy_tdt_tokens_are_at_least_as_likely_as_the_greedy_path(
    models: Dict[str, Path], seed: int
) -> None:
    model, frames = _encoded(models["tdt"], seed)
    tokens, moves = _greedy_moves(model, frames, TDT_DURATIONS)
    lattice = model.lattice(frames, tokens, BLANK)
    split = lattice.shape[-1] - len(TDT_DURATIONS)
    token_lp, duration_lp = log_softmax(lattice[..., :split]), log_softmax(lattice[..., split:])
    # greedy's path on the lattice, an alignment as it is on this model: each step where the last
    # move left it, no blank staying, the last a blank landing exactly on T'
    t = u = 0
    path_score = 0.0
    for frame, token, duration in moves:
        assert frame == t
        assert token != BLANK or TDT_DURATIONS[duration] > 0
        path_score += token_lp[t, u, token] + duration_lp[t, u, duration]
        t, u = t + TDT_DURATIONS[duration], u + int(token != BLANK)
    assert (t, u) == (len(frames), len(tokens))
    assert moves[-1][1] == BLANK
    assert len(tokens) > 0
    assert path_score <= tdt_log_likelihood(lattice, tokens, BLANK, TDT_DURATIONS) < 0.0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_greedy_ctc_tokens_are_at_least_as_likely_as_the_greedy_path(
    models: Dict[str, Path], seed: int
) -> None:
    model = CtcModel(models["ctc"])
    feature_settings = load_manifest(models["ctc"] / MANIFEST_FILE).features
    logits = model.logits(features(padded_as_nemo_does(_audio(seed), 16000), feature_settings))
    found = ctc_greedy(logits, BLANK)  # its score is its path's: every frame's best token
    assert found.tokens
    assert found.score <= ctc_log_likelihood(logits, found.tokens, BLANK) < 0.0


@pytest.mark.parametrize("kind", ["rnnt", "tdt"])
def test_the_lattice_is_the_joint_at_every_frame_after_every_prefix(
    models: Dict[str, Path], kind: str
) -> None:
    model, frames = _encoded(models[kind], 0)
    tokens = VOCABULARY.encode("hello")
    lattice = model.lattice(frames, tokens, BLANK)
    assert lattice.shape[:2] == (len(frames), len(tokens) + 1)
    state, last = model.initial_state(), BLANK
    for u in range(len(tokens) + 1):
        for t, frame in enumerate(frames):
            logits, _ = model.step(frame, last, state)
            np.testing.assert_allclose(lattice[t, u], logits, rtol=0, atol=1e-5)
        _, state = model.step(frames[0], last, state)  # the state after a token: any frame's
        if u < len(tokens):
            last = tokens[u]


PHRASES = ["go", "go left", "go lift", "go left now", "go right", "stop", "stop now", ""]


def _counted_joint(monkeypatch: pytest.MonkeyPatch, model: TransducerModel) -> List[int]:
    """The tokens of each decoder-joint call, counted."""
    calls: List[int] = []
    joint = model.joint

    def counted(frames: np.ndarray, last_tokens: Sequence[int], *rest: Any) -> Any:
        calls.append(len(last_tokens))
        return joint(frames, last_tokens, *rest)

    monkeypatch.setattr(model, "joint", counted)
    return calls


@pytest.mark.parametrize("where_greedy_stops", [False, True])  # TDT past_end, RNN-T one_per_frame
@pytest.mark.parametrize("one_node_a_call", [False, True])
@pytest.mark.parametrize("kind", ["rnnt", "tdt"])
def test_the_trie_scores_every_sequence_as_scoring_it_alone_calling_the_joint_once_per_prefix(
    models: Dict[str, Path],
    monkeypatch: pytest.MonkeyPatch,
    kind: str,
    one_node_a_call: bool,
    where_greedy_stops: bool,
) -> None:
    model, frames = _encoded(models[kind], 1)
    sequences = [VOCABULARY.encode(phrase) for phrase in PHRASES]
    lattices = [model.lattice(frames, s, BLANK) for s in sequences]
    if kind == "tdt":
        alone = [
            tdt_log_likelihood(lattice, s, BLANK, TDT_DURATIONS, where_greedy_stops)
            for lattice, s in zip(lattices, sequences)
        ]
    else:
        alone = [
            rnnt_forward(
                *blank_and_token_log_probabilities(log_softmax(lattice), s, BLANK),
                one_per_frame=where_greedy_stops,
            )
            for lattice, s in zip(lattices, sequences)
        ]
    if one_node_a_call:  # the rows cap splits the nodes of a depth: here to one a call
        monkeypatch.setattr(phrase_scores, "MAX_ROWS", 1)
    calls = _counted_joint(monkeypatch, model)
    if kind == "tdt":
        together = tdt_scores(model, frames, sequences, BLANK, TDT_DURATIONS, where_greedy_stops)
    else:
        together = rnnt_scores(model, frames, sequences, BLANK, where_greedy_stops)
    assert together == alone  # exactly: all phrases in one forward pass, each as it is alone
    assert len(set(together)) == len(together)
    prefixes = {tuple(s[:u]) for s in sequences for u in range(len(s) + 1)}
    assert sum(calls) == len(prefixes)  # each prefix once, all sequences sharing it
    deepest = max(len(s) for s in sequences)
    assert len(calls) == (len(prefixes) if one_node_a_call else deepest + 1)  # else a depth a call


def test_the_spoken_phrase_scores_higher_than_near_misses_on_the_tones_model() -> None:
    directory = tones_tdt_model_directory()
    manifest, vocabulary = (
        load_manifest(directory / MANIFEST_FILE),
        load_vocabulary(directory / VOCABULARY_FILE),
    )
    model = TransducerModel(directory)
    audio = speak_tones("go left", 16000)
    frames = model.encode(features(padded_as_nemo_does(audio, 16000), manifest.features))
    # a letter changed, a letter or a word missing; not a letter more: off the tones the fixture's blank
    # (logit 0.5 against 0 for each of 53 tokens) has 3 %, a token 1.8 %, so a letter more, one of ~100
    # places, is the likelier
    phrases = ["go left", "go lift", "go let", "go", "left"]
    scores = tdt_scores(
        model, frames, [vocabulary.encode(p) for p in phrases], vocabulary.blank, manifest.durations
    )
    assert scores[0] == max(scores)
    assert scores[0] - sorted(scores)[-2] > 5.0


def test_encode_spells_words_by_the_longest_pieces_that_spell_the_whole_word() -> None:
    pieces = [
        "<unk>",
        "\u2581go",
        "\u2581g",
        "o",
        "\u2581le",
        "ft",
        "f",
        "t",
        "\u2581",
        "\u2581ab",
        "\u2581a",
        "bc",
    ]
    vocabulary = Vocabulary([*pieces, "<blk>"])
    ids = {piece: i for i, piece in enumerate(pieces)}
    assert vocabulary.encode("go left") == [ids["\u2581go"], ids["\u2581le"], ids["ft"]]
    assert vocabulary.encode("  Go   LEFT ") == vocabulary.encode("go left")
    assert vocabulary.encode("ft") == [ids["\u2581"], ids["ft"]]  # the bare word-start mark, then the word
    # "\u2581ab" would leave "c", which no piece spells: the shorter "\u2581a" then "bc"
    assert vocabulary.encode("abc") == [ids["\u2581a"], ids["bc"]]
    assert vocabulary.encode("") == []
    for text in ["go left", "ft", "abc", "gooft"]:
        assert vocabulary.text(vocabulary.encode(text)) == text


@pytest.mark.parametrize("word", ["lefx", "<unk>", "x"])
def test_encode_names_a_word_the_vocabulary_cannot_spell(word: str) -> None:
    vocabulary = Vocabulary(["<unk>", "\u2581le", "f", "t", "<blk>"])
    with pytest.raises(ModelError) as error:
        vocabulary.encode(f"left {word} left")
    assert str(error.value) == (
        f"the model's vocabulary has no pieces for the word {word!r}: it cannot be spelt as a word-start "
        "piece (\u2581...) then inner pieces"
    )


def test_encode_on_the_fixture_vocabulary_gives_back_the_text(models: Dict[str, Path]) -> None:
    vocabulary = load_vocabulary(models["rnnt"] / VOCABULARY_FILE)
    ids = vocabulary.encode("muraho rwanda")
    assert vocabulary.text(ids) == "muraho rwanda"
    assert ids[0] == PIECES.index("\u2581m") and ids[1] == PIECES.index("u")
