"""bench/figures/end_of_speech.py's model of the robot's gate, which (e) measures splits and speculation
behind, the pauses (f) counts splits against, and (f)'s four rules."""

import numpy as np

from bench.figures.end_of_speech import BLOCK, RATE, gated, pauses_inside, turn_end_rules
from speech_event.config import SpeechEventConfig


def test_the_gate_passes_whole_blocks_at_or_over_sound_detections_threshold_at_their_times() -> None:
    audio = np.concatenate(
        [
            np.full(BLOCK, 0.5),  # the loudest block: set to an RMS of 0.1
            np.full(BLOCK, 0.005),  # 0.001 once set: under intensityThreshold (0.0039), a pause
            np.full(BLOCK, 0.02),  # 0.004: over it
            np.full(BLOCK // 2, 0.5),  # no whole block: soundDetection has not sent it yet
        ]
    )
    blocks = gated(audio)
    assert [when for when, _ in blocks] == [BLOCK / RATE, 3 * BLOCK / RATE]
    assert np.array_equal(blocks[0][1], np.full(BLOCK, 0.1, np.float32))
    assert np.array_equal(blocks[1][1], np.full(BLOCK, 0.004, np.float32))


def test_a_pause_is_a_fifth_of_a_second_or_more_30_db_under_the_loudest_between_sounds() -> None:
    def tone(seconds: float, level: float = 0.5) -> np.ndarray:
        return np.full(int(seconds * RATE), level)

    quiet = 0.5 * 10**-2.5  # 50 dB under the loudest: a pause
    audio = np.concatenate(
        [
            tone(0.3, 0.0),  # before the first sound: no pause inside
            tone(0.5),
            tone(0.3, quiet),  # a pause
            tone(0.5),
            tone(0.1, 0.0),  # too short
            tone(0.5),
            tone(0.3, 0.05),  # 20 dB under: speech still
            tone(0.5),
            tone(0.24, 0.0),  # a pause
            tone(0.5),
            tone(1.0, 0.0),  # after the last: none
        ]
    )
    assert pauses_inside(audio) == 2


def test_the_four_rules_are_the_pause_the_text_smart_turn_alone_and_both() -> None:
    rules = turn_end_rules(SpeechEventConfig(end_of_speech=0.0), 0.3)
    assert list(rules) == ["pause only", "text alone", "Smart Turn alone", "text and Smart Turn"]
    assert [(rule.end_of_speech, rule.turn_end_model, rule.turn_end_text) for rule in rules.values()] == [
        (0.0, "none", True),
        (0.3, "none", True),
        (0.3, "smart-turn", False),
        (0.3, "smart-turn", True),
    ]
