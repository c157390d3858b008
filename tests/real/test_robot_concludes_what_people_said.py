"""Trained Whisper (tiny.en) in free speech as the robot listens (issue 57, item 1): Whisper writes
" Yes.", in which the Behaviour Controller's case-sensitive search finds no "yes"; written as the
robot's NeMo model writes (text_style robot, the default), the robot concludes what people said."""

from harness.behaviour_controller import NO, NOTHING, YES, conclusion
from tests.helpers.people_answering import answers_heard


def test_the_robot_concludes_yes_and_no_from_what_whisper_heard_people_say() -> None:
    heard = answers_heard("whisper-tiny.en")
    assert [(h.said, h.concluded) for h in heard] == [
        *[("yes", YES)] * 8,
        *[("no", NO)] * 8,
        *[("go", YES)] * 8,
    ]
    assert {h.text for h in heard} == {"yes", "no", "now", "go"}  # "no" is in "now", as it searches
    # as Whisper writes them, the robot would have concluded nothing from any
    assert {h.written for h in heard} == {"Yes.", "No.", "Now.", "Go!", "Go"}
    assert {conclusion(h.written) for h in heard} == {NOTHING}
