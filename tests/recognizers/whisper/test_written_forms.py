"""The forms a phrase is scored in: Whisper's usual ones, and the phrase written as the free text is."""

import pytest

from speech_event.recognizers.whisper.written_forms import (
    aligned,
    phrase_as_written,
    phrase_variants,
    written_words,
)


def test_phrase_variants_are_whispers_surface_forms() -> None:
    assert phrase_variants("go left") == [" go left", " go left.", " Go left", " Go left."]
    assert phrase_variants("  Go   left. ") == [" go left", " go left.", " Go left", " Go left."]
    assert phrase_variants("42") == [" 42", " 42."]  # no capital: no duplicates
    with pytest.raises(ValueError):
        phrase_variants(" . ")


def test_written_words_keep_each_words_writing_punctuation_and_capital() -> None:
    assert written_words(' "Eight of spades, 25 of close, 7?" ') == [
        ("eight", "Eight", '"', "", True),
        ("of", "of", "", "", False),
        ("spades", "spades", "", ",", False),
        # "25" in words: each written as itself, the first takes what is before, the last what is after
        ("twenty", "twenty", "", "", False),
        ("five", "five", "", "", False),
        ("of", "of", "", "", False),
        ("close", "close", "", ",", False),
        ("seven", "7", "", '?"', False),
    ]
    assert written_words(" Go - left-hand ... ") == [  # punctuation between words or inside one: left out
        ("go", "Go", "", "", True),
        ("left", "left", "", "", False),
        ("hand", "hand", "", "", False),
    ]
    assert written_words(" ... ") == []


def test_phrase_words_are_aligned_with_the_words_heard_in_their_place() -> None:
    assert aligned(["what", "is", "your", "name"], ["what", "is", "it", "your", "name"]) == [0, 1, 3, 4]
    assert aligned(["tell", "me", "a", "joke"], ["tell", "me", "joke"]) == [0, 1, None, 2]
    assert aligned(["play", "some", "music"], ["place", "a", "music"]) == [0, 1, 2]
    assert aligned(["go", "to", "the"], ["goto", "the"]) == [None, 0, 1]  # read back from the end
    assert aligned(["go"], []) == [None]
    assert aligned([], ["go"]) == []


def test_a_phrase_is_written_as_the_free_text_is() -> None:
    assert (
        phrase_as_written(
            "eight of spades four of clubs seven of hearts",
            " Eight of spades, four of close, seven of hearts.",
        )
        == " Eight of spades, four of clubs, seven of hearts."
    )
    assert phrase_as_written("what is your name", " What is it your name?") == " What is your name?"
    assert phrase_as_written("play some music", " Place a music.") == " Play some music."
    assert (
        phrase_as_written("tell me a joke", " Tell me, Joke.") == " Tell me, a Joke."
    )  # "a" not heard: bare
    # a word heard as said is written as heard: its digits, its capitals
    assert (
        phrase_as_written(
            "eight of spades four of clubs seven of hearts", " 8 of spades, 4 of close, 7 of hearts."
        )
        == " 8 of spades, 4 of clubs, 7 of hearts."
    )
    assert phrase_as_written("four queen of clubs", " 4. Queen of Clothes") == " 4. Queen of Clubs"
    assert phrase_as_written("go left", " GO LEFT.") == " GO LEFT."
    assert (
        phrase_as_written("set volume to twenty five", " Set volume to 25.") == " Set volume to twenty five."
    )
    assert phrase_as_written("go left", "") == " go left"
    # the free text's opening and closing go to the phrase's ends, whatever the words in between
    assert phrase_as_written("go to the kitchen", " Goto the kitchen.") == " Go to the kitchen."
    assert phrase_as_written("turn the lights off", " Turn the lights.") == " Turn the lights off."
    assert phrase_as_written("go left", " Go left, now.") == " Go left."
    assert phrase_as_written("come here", " So, come here!") == " Come here!"  # heard as said, at the start
    assert phrase_as_written("go", ' "Go!"') == ' "Go!"'
