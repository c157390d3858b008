"""How a free decoding is compared with a phrase by sound (onnx/sounds_alike.py): pronunciations from
pocketsphinx's CMU dictionary, edits phone by phone, and the share that makes a command misheard."""

from hypothesis import given
from hypothesis import strategies as st

from speech_event.recognizers.onnx.grammar_choice import SOUND_ALIKE_SHARE
from speech_event.recognizers.onnx.sounds_alike import Phones, phone_edits, pronunciations, sounds_alike

phones = st.lists(st.sampled_from(["AA", "AE", "D", "N", "S", "Z"]), max_size=8).map(tuple)


def test_a_words_pronunciations_are_the_dictionarys_in_its_order() -> None:
    assert pronunciations("the") == [("DH", "AH"), ("DH", "IY")]  # "the" and "the(2)"
    assert pronunciations("thank you") == [("TH", "AE", "NG", "K", "Y", "UW")]
    assert pronunciations("'bout") == [("B", "AW", "T")]  # the dictionary's first line
    assert pronunciations("dan's") == [("D", "AE", "N", "Z")]


def test_a_text_with_a_word_the_dictionary_lacks_has_no_pronunciation_and_sounds_like_nothing() -> None:
    assert pronunciations("murakoze cyane") == []  # Kinyarwanda
    assert pronunciations("thank xyzzy") == []
    assert pronunciations("") == []
    assert not sounds_alike("murakoze", "murakoze", SOUND_ALIKE_SHARE)


def test_phone_edits_count_phones_changed_added_and_dropped() -> None:
    assert phone_edits(("D", "AE", "N", "S"), ("D", "AE", "N", "Z")) == 1
    assert phone_edits(("D", "AE", "N"), ("D", "AE", "N", "S")) == 1
    assert phone_edits(("S", "T", "AA", "P", "S"), ("S", "T", "AA", "P")) == 1
    assert phone_edits((), ("D", "AE")) == 2
    assert phone_edits(("L", "AE", "F", "T", "ER"), ("L", "AW", "D", "ER")) == 3


@given(phones, phones, phones)
def test_phone_edits_is_a_distance(one: Phones, other: Phones, third: Phones) -> None:
    assert phone_edits(one, one) == 0
    assert phone_edits(one, other) == phone_edits(other, one)
    assert phone_edits(one, third) <= phone_edits(one, other) + phone_edits(other, third)
    assert abs(len(one) - len(other)) <= phone_edits(one, other) <= max(len(one), len(other))


def test_commands_a_trained_whisper_heard_as_sound_alike_words_sound_alike() -> None:
    """What Whisper tiny.en and base wrote for festival's ked voice (issue 32, docs/grammar.md)."""
    assert sounds_alike("place a music", "play some music", SOUND_ALIKE_SHARE)  # 1 phone of 12
    assert sounds_alike("tell me joke", "tell me a joke", SOUND_ALIKE_SHARE)  # 1 of 9
    assert sounds_alike("what is it your name", "what is your name", SOUND_ALIKE_SHARE)  # 2 of 11


def test_near_misses_and_other_speech_do_not() -> None:
    assert not sounds_alike("thanks", "thank you", SOUND_ALIKE_SHARE)  # 2 of 6: a third
    assert not sounds_alike(
        "go to the kitchen later", "go to the kitchen", SOUND_ALIKE_SHARE
    )  # 4 more than 11
    # within a quarter, but said after the command: its last phone is not the command's
    assert not sounds_alike("go to the kitchen now", "go to the kitchen", SOUND_ALIKE_SHARE)  # 2 more than 11
    assert not sounds_alike("so go to the kitchen", "go to the kitchen", SOUND_ALIKE_SHARE)  # ... before it
    assert not sounds_alike("how old are you", "how are you", SOUND_ALIKE_SHARE)  # 3 of 5
    assert not sounds_alike("tell me a story", "tell me a joke", SOUND_ALIKE_SHARE)
    assert not sounds_alike(
        "wait lord hand", "wave your hand", SOUND_ALIKE_SHARE
    )  # 3 of 10, beyond a quarter
    assert sounds_alike("wait lord hand", "wave your hand", share=0.3)
