"""Whisper's tokenizer: tiktoken's byte-pair merges on GPT-2's words, by hand on small vocabularies,
and against Hugging Face's tokenizer (the ``tokenizers`` package, merges and all) on trained
tiny.en's vocabulary, whose tokenizer.json ships beside its model.bin."""

from dataclasses import dataclass
from typing import List

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from tokenizers import Tokenizer

from fixtures.paths import ROOT
from fixtures.trained_whisper import tiny_en_directory
from fixtures.whisper_tones_model import MANIFEST, TIMESTAMP_BEGIN, whisper_tones_model_directory
from speech_event.errors import ModelError
from speech_event.exporters.faster_whisper import read_vocabulary, token_pieces
from speech_event.recognizers.whisper.manifest import load_tokens, text_of
from speech_event.recognizers.whisper.tokenizer import WhisperTokenizer, word_pattern
from speech_event.recognizers.whisper.written_forms import phrase_variants


@dataclass(frozen=True)
class TinyEn:
    """tiny.en's token texts, our tokenizer of them and Hugging Face's of its tokenizer.json."""

    texts: List[str]
    ours: WhisperTokenizer
    reference: Tokenizer

    def spelt(self, text: str) -> List[str]:
        return [self.texts[token] for token in self.ours.encode(text)]

    def agree(self, text: str) -> bool:
        expected: List[int] = self.reference.encode(text, add_special_tokens=False).ids
        return self.ours.encode(text) == expected


@pytest.fixture(scope="module")
def tiny_en() -> TinyEn:
    folder = tiny_en_directory()
    texts, source = read_vocabulary(folder)
    ours = WhisperTokenizer(token_pieces(texts, source), texts.index("<|endoftext|>"))
    return TinyEn(texts, ours, Tokenizer.from_file(str(folder / "tokenizer.json")))


def _pieces(tokenizer: WhisperTokenizer, text: str, pieces: List[bytes]) -> List[bytes]:
    return [pieces[token] for token in tokenizer.encode(text)]


def test_words_are_cut_by_gpt2s_pattern() -> None:
    assert word_pattern().findall(" don't go  left, 42x\u00b2 \u00e9t\u00e9\n") == [
        " don",
        "'t",
        " go",
        " ",
        " left",
        ",",
        " 42",
        "x",
        "\u00b2",  # a number (No), not a letter, though Python's \w takes it
        " \u00e9t\u00e9",
        "\n",
    ]
    assert word_pattern().findall("a_b\u3000 c") == ["a", "_", "b", "\u3000", " c"]  # "_" is no letter


def test_the_lowest_ranked_pair_merges_first_and_a_word_that_is_a_token_is_that_token() -> None:
    pieces = [b"a", b"b", b"c", b" ", b"bc", b"ab", b"aa", b"xyz", b"x", b"y", b"z", b"<|endoftext|>"]
    tokenizer = WhisperTokenizer(pieces, 11)
    # "bc" ranks before "ab": the longest match from the left would give "ab" + "c"
    assert _pieces(tokenizer, "abc", pieces) == [b"a", b"bc"]
    assert _pieces(tokenizer, "aaa", pieces) == [b"aa", b"a"]  # equals: the leftmost
    # no pair of it is a token, yet the word is: tiktoken takes it whole
    assert _pieces(tokenizer, "xyz", pieces) == [b"xyz"]
    assert _pieces(tokenizer, "xyzz", pieces) == [b"x", b"y", b"z", b"z"]
    assert _pieces(tokenizer, "b abc", pieces) == [b"b", b" ", b"a", b"bc"]


def test_a_part_that_no_text_token_is_is_named() -> None:
    pieces = [b"a", b"b", b"<|", b"|>", b"<|endoftext|>", b"<|endoftext|>"]
    with pytest.raises(ModelError) as error:
        WhisperTokenizer(pieces, 4).encode("<|endoftext|>")  # the special token is not a text token
    assert str(error.value) == "the model's text tokens cannot spell '<|endoftext|>': no token is b'e'"
    with pytest.raises(ModelError) as error:
        WhisperTokenizer(pieces, 4).encode("ab\u00e9")
    assert str(error.value) == "the model's text tokens cannot spell 'ab\u00e9': no token is b'\\xc3'"


def test_the_tones_models_words_are_a_word_start_letter_then_inner_letters() -> None:
    tokens = load_tokens(whisper_tones_model_directory() / "tokens.txt")
    tokenizer = WhisperTokenizer(tokens, MANIFEST.eot)
    for text in (" go left", " go to the kitchen", " don't stop"):
        assert text_of(tokenizer.encode(text), tokens, TIMESTAMP_BEGIN) == text
    assert _pieces(tokenizer, " go", tokens) == [b" g", b"o"]
    with pytest.raises(ModelError) as error:
        tokenizer.encode(" Go left.")  # the tones model has no capitals: that variant is not its to write
    assert str(error.value) == "the model's text tokens cannot spell ' Go left.': no token is b' '"


def test_tiny_en_spells_spades_as_its_tokenizer_does(tiny_en: TinyEn) -> None:
    # longest match took " spa" + "des", which the model gives 16 nats less than its own spelling
    assert tiny_en.spelt(" Eight of spades.") == [
        "\u0120Eight",
        "\u0120of",
        "\u0120sp",
        "ades",
        ".",
    ]


def test_every_form_of_the_robots_commands_and_of_everyday_sentences_is_tokenized_as_hugging_faces(
    tiny_en: TinyEn,
) -> None:
    sentences = [
        line
        for path in (
            ROOT / "harness" / "data" / "robot_commands.txt",
            ROOT / "bench" / "data" / "out_of_grammar.txt",
        )
        for line in path.read_text().splitlines()
        if line.strip() and not line.startswith("#")
    ]
    assert len(sentences) == 32 + 65
    for sentence in sentences:
        for form in phrase_variants(sentence):
            assert tiny_en.agree(form), form
    # the command longest match spelt otherwise
    assert tiny_en.spelt(" Louder") == ["\u0120Lou", "der"]


TEXT = st.lists(
    st.sampled_from(
        [
            *"abcxyzABXZ   '.,!?-_0123456789\u00e9\u00fc\u00f1\u00df\u00b2\u00bd\u216b\t\n\u00a0\u3000\u65e5\u672c",
            *["'s", "'ll", "'re", "  ", " the", " kitchen", "Rwanda", " muraho"],
        ]
    ),
    max_size=24,
).map("".join)


@settings(max_examples=300, deadline=None)
@given(TEXT)
def test_any_text_is_tokenized_as_hugging_faces_tokenizer_does(tiny_en: TinyEn, text: str) -> None:
    assert tiny_en.agree(text)
