"""bench/end_of_speech.py's model of the robot's gate, which (e) measures splits and speculation behind."""

import numpy as np

from bench.end_of_speech import BLOCK, RATE, gated


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
