"""bench/figures/robot_conclusions.py's tally: right, wrong (a yes or no nobody said) and missed (a yes or
no said, not concluded), by the Behaviour Controller's rule on what was said and what was published."""

from bench.figures.robot_conclusions import Conclusions


def test_each_clip_counts_as_right_wrong_or_missed_by_the_controllers_rule() -> None:
    tally = Conclusions()
    tally.add("yes", "yes")  # right
    tally.add("go", "go")  # right: a yes word
    tally.add("no", "")  # missed
    tally.add("yes", "no")  # missed, and wrong: a no nobody said
    tally.add("four", "")  # right: nothing said, nothing concluded
    tally.add("down", "known")  # wrong: "no" is in "known"
    tally.add("Good morning.", "good morning")  # right: the reading says "go", as the robot reads it
    assert (tally.clips, tally.right, tally.wrong, tally.answers, tally.missed) == (7, 4, 2, 5, 2)
    assert tally.line("set") == "  set                 7 clips  right    4  wrong 2 (28.6 %)  missed 2 of 5"
