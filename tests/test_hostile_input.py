"""Whatever an in-process publisher hands the node, the speech around it is transcribed exactly,
nothing raises out of the callback, and nothing is left in the assembler."""

import logging
from types import SimpleNamespace
from typing import Any, List

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from fixtures.audio import speak_tones
from fixtures.rig import Rig
from speech_event.config import SpeechEventConfig
from speech_event.messages import Float32MultiArray, MultiArrayDimension, String
from speech_event.recognizers.tones import ToneRecognizer

CONFIG = SpeechEventConfig(sample_rate=16000, health_check_period=3600.0, max_message_length=1.0)
SPEECH = speak_tones("go left", 16000)

# Every strategy below draws only objects that are no usable audio, by construction: the test
# does not ask the validator which they are.
not_sequences = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=5),
    st.binary(max_size=8),
    st.dictionaries(st.text(max_size=3), st.integers(), max_size=3),
    st.builds(lambda values: (value for value in values), st.lists(st.floats(), max_size=3)),
)
audio_like = st.floats(-1.0, 1.0, width=32)
not_flat = st.one_of(
    # plausible audio of the wrong shape: a scalar, 2-D or 3-D
    hnp.arrays(np.float32, hnp.array_shapes(min_dims=2, max_dims=3, max_side=6), elements=audio_like),
    hnp.arrays(np.float32, (), elements=audio_like),
    st.lists(st.lists(audio_like, min_size=1, max_size=3), min_size=1, max_size=3),  # nested, maybe ragged
    hnp.arrays(
        st.sampled_from([np.dtype(object), np.dtype(bool), np.dtype("U2")]), hnp.array_shapes(max_dims=1)
    ),
)
not_in_range = st.lists(audio_like, min_size=1, max_size=6).flatmap(
    lambda samples: st.sampled_from([float("nan"), float("inf"), -2.0, 1e300, 32767.0]).map(
        lambda bad: [*samples, bad]
    )
)
bad_data = st.one_of(not_sequences, not_flat, not_in_range)
bad_dims = st.one_of(
    st.none(),
    st.integers(),
    st.lists(
        st.builds(SimpleNamespace, size=st.one_of(st.none(), st.text(max_size=2), st.integers(-3, -1))),
        min_size=1,
        max_size=2,
    ),
)
good_dims = st.lists(
    st.builds(MultiArrayDimension, st.text(max_size=3), st.integers(0, 1), st.integers(0, 10)), max_size=2
)
hostile = st.one_of(
    bad_data,  # not a message at all
    st.builds(Float32MultiArray, data=bad_data),
    st.builds(
        lambda d, dim: SimpleNamespace(
            _type="std_msgs/Float32MultiArray", data=d, layout=SimpleNamespace(dim=dim)
        ),
        bad_data,
        good_dims,
    ),
    st.builds(
        lambda dim: SimpleNamespace(
            _type="std_msgs/Float32MultiArray", data=[0.1], layout=SimpleNamespace(dim=dim)
        ),
        bad_dims,
    ),
    st.builds(
        lambda d: SimpleNamespace(_type="std_msgs/Float32MultiArray", data=d),
        st.lists(audio_like, min_size=1),
    ),
    st.builds(lambda: SimpleNamespace(_type="std_msgs/Float32MultiArray", layout=SimpleNamespace(dim=[]))),
    st.builds(String, st.text(max_size=5)),
)


@settings(max_examples=200, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(hostile, min_size=1, max_size=12), st.randoms(use_true_random=False))
def test_hostile_objects_between_speech_blocks_change_nothing(objects: List[Any], random: Any) -> None:
    rig = Rig(CONFIG, ToneRecognizer())
    messages: List[object] = [
        Float32MultiArray(data=SPEECH[start : start + 1024]) for start in range(0, SPEECH.size, 1024)
    ]
    for obj in objects:
        messages.insert(random.randrange(len(messages) + 1), obj)
    for message in messages:
        rig.clock.advance(0.01)
        rig.sound_detection.publish(message)  # an exception out of the callback fails the test
    rig.clock.advance(2.0)
    assert rig.texts() == ["go left"]
    assert rig.node.pending_samples == 0
    assert sum(rig.node.rejection_counts.values()) == len(objects)  # each named, none taken as audio


def test_no_failure_is_left_to_the_callbacks_last_guard(caplog: pytest.LogCaptureFixture) -> None:
    """The guard in on_signal logs what validation missed; for these it must stay silent."""
    rig = Rig(CONFIG, ToneRecognizer())
    with caplog.at_level(logging.ERROR, logger="speech_event"):
        no_data = Float32MultiArray(data=None)  # type: ignore[arg-type]
        objects: List[object] = [None, 3, "x", b"x", {}, [[1], [1, 2]], np.zeros((2, 2)), no_data]
        for obj in objects:
            rig.sound_detection.publish(obj)
    assert caplog.records == []
    assert rig.node.rejection_counts["malformed"] == 1  # the Float32MultiArray with no data
    assert rig.node.rejection_counts["wrong_type"] == 7  # the rest are no message at all
