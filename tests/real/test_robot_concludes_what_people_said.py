"""Trained Whisper (tiny.en) in free speech as the robot listens (issue 57, item 1): Whisper writes
" Yes.", in which the Behaviour Controller's case-sensitive search finds no "yes"; written as the
robot's NeMo model writes (text_style robot, the default), the robot concludes what people said.

Only the conclusions are asserted, and how each text is written from the engine's: which word
Whisper writes for a clip ("No." or "Now.", both a no to the controller) is a near tie its CPU's
kernels may decide."""

from fixtures.people_answering import answers_heard
from harness.behaviour_controller import NO, NOTHING, YES, conclusion
from speech_event.spelling import robot_written


def test_the_robot_concludes_yes_and_no_from_what_whisper_heard_people_say() -> None:
    heard = answers_heard("whisper-tiny.en")
    assert [(h.said, h.concluded) for h in heard] == [
        *[("yes", YES)] * 4,
        *[("no", NO)] * 4,
        *[("go", YES)] * 4,
    ]
    assert all(h.text == robot_written(h.written) for h in heard)
    # as Whisper writes them, the robot would have concluded nothing from any
    assert {conclusion(h.written) for h in heard} == {NOTHING}
