"""bench/figures/talk_then_command.py's talk and command, as the robot's gate passes them."""

import numpy as np

from bench.figures.end_of_speech import BLOCK, INTENSITY_THRESHOLD, RATE
from bench.figures.talk_then_command import BEFORE_THE_COMMAND, command, talk
from fixtures.noises import rms


def test_the_talk_is_recordings_one_after_another_for_at_least_the_seconds_asked_behind_the_gate() -> None:
    blocks, seconds = talk(20.0)
    times = [when for when, _ in blocks]
    assert times == sorted(times) and len(set(times)) == len(times)
    assert 20.0 <= seconds < 35.0 and times[-1] <= seconds + 1e-9
    assert all(block.dtype == np.float32 and block.size == BLOCK for _, block in blocks)
    assert all(rms(block) >= INTENSITY_THRESHOLD for _, block in blocks)  # what the gate lets through
    assert np.diff(times).max() > BLOCK / RATE  # pauses: the gate sends nothing there
    assert talk(0.0) == ([], 0.0)


def test_the_command_comes_after_the_talk_and_its_pause() -> None:
    _, seconds = talk(5.0)
    said = command(seconds + BEFORE_THE_COMMAND)
    assert said[0][0] >= seconds + BEFORE_THE_COMMAND + BLOCK / RATE
    assert all(rms(block) >= INTENSITY_THRESHOLD for _, block in said)
