"""pocketsphinx, the node's embedded English engine, in free speech as the robot listens: what the
Behaviour Controller concludes from what the node publishes for people saying "yes", "no" and "go"
(trained Whisper: tests/real/test_robot_concludes_what_people_said.py)."""

from fixtures.people_answering import answers_heard
from harness.behaviour_controller import NO, NOTHING, YES


def test_the_robot_concludes_what_people_said_but_for_a_go_pocketsphinx_misheard() -> None:
    heard = answers_heard("pocketsphinx")
    assert [(h.said, h.concluded) for h in heard] == [
        *[("yes", YES)] * 4,
        *[("no", NO)] * 4,  # one heard as 'known': "no" is in it, as the controller searches
        ("go", YES),
        ("go", NOTHING),  # heard as 'there are'
        *[("go", YES)] * 2,
    ]
    assert [h.text for h in heard if h.text not in ("yes", "no", "go")] == ["known", "there are"]
