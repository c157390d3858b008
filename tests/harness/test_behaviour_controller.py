"""The Behaviour Controller's rule (harness/behaviour_controller.py) as its C++ reads texts:
case-sensitive substrings, the latest text of each second, an error fails, 10 s and it gives up;
and what it concludes from texts as each engine and text_style writes them."""

import pytest

from harness.behaviour_controller import FAILURE, NO, NOTHING, YES, conclusion, visitor_response
from speech_event.pipeline.transcript import styled


@pytest.mark.parametrize(
    ("text", "concluded"),
    [
        ("yes", YES),
        (" Yes.", NOTHING),  # Whisper's writing: "Yes" is not "yes"
        ("No thank you.", NOTHING),
        ("no thank you", NO),
        ("i know", NO),  # a substring: "no" is in "know"
        ("good morning", YES),  # "go" and "good"
        ("go", YES),
        ("Error: soundDetection is down", FAILURE),
        ("maybe later", NOTHING),
    ],
)
def test_a_text_concludes_what_the_controllers_substring_search_finds(text: str, concluded: str) -> None:
    assert conclusion(text) == concluded


def test_kinyarwanda_has_its_own_words() -> None:
    assert [conclusion(text, "kinyarwanda") for text in ("yego", "oya", "no", "ntakibazo cyane")] == [
        YES,
        NO,
        NOTHING,
        YES,
    ]


def test_the_latest_text_of_a_second_is_read_and_after_ten_seconds_it_gives_up() -> None:
    assert visitor_response([(0.2, "yes"), (0.7, "maybe")]) == NOTHING  # 'yes' overwritten unread
    assert visitor_response([(0.2, "maybe"), (1.5, "no")]) == NO
    assert visitor_response([(10.5, "yes")]) == YES  # read at the tick at 11 s, then it gives up
    assert visitor_response([(11.5, "yes")]) == NOTHING
    assert visitor_response([(3.0, "yes")], asked_at=2.5) == YES


@pytest.mark.parametrize("said", [" Yes.", "Yes!", "YES.", " No.", "No, thank you.", " Go!", "Good."])
def test_in_the_robots_style_whispers_yes_and_no_are_the_robots(said: str) -> None:
    assert conclusion(said) == NOTHING
    assert conclusion(styled(said, "robot")) in (YES, NO)
    assert conclusion(styled(said, "engine")) == NOTHING
