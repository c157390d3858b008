import logging
from types import SimpleNamespace
from typing import List

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from fixtures.malformed import malformed_message
from speech_event.messages import Float32MultiArray, MultiArrayDimension, MultiArrayLayout
from speech_event.pipeline.rejections import RejectionLog
from speech_event.pipeline.validate import Accepted, Reason, Rejection, validate_signal

RATE = 48000
CAP = 60 * RATE


def _message(data: object, dim: object = ()) -> object:
    return SimpleNamespace(_type="std_msgs/Float32MultiArray", layout=SimpleNamespace(dim=dim), data=data)


@pytest.mark.parametrize(
    ("kind", "reason", "detail_start"),
    [
        ("empty", Reason.EMPTY, "empty data (allowed: 1 or more float32 samples)"),
        ("nan", Reason.NON_FINITE, "3 of 4096 samples are NaN or Inf (allowed: finite values in [-1, 1])"),
        ("inf", Reason.NON_FINITE, "3 of 4096 samples are NaN or Inf (allowed: finite values in [-1, 1])"),
        ("out_of_range", Reason.OUT_OF_RANGE, "peak value "),
        (
            "multichannel",
            Reason.MULTI_DIMENSIONAL,
            "layout has dimensions 2 x 4096 (allowed: mono audio, an empty layout or one dimension)",
        ),
        (
            "oversized",
            Reason.OVERSIZED,
            "2928000 samples in one message (allowed: at most 2880000, set by max_message_length)",
        ),
        (
            "wrong_type",
            Reason.WRONG_TYPE,
            "message of type std_msgs/String (allowed: std_msgs/Float32MultiArray with mono float32 samples)",
        ),
    ],
)
def test_each_malformed_kind_is_rejected_with_its_reason_and_what_is_allowed(
    kind: str, reason: Reason, detail_start: str
) -> None:
    # seed 3 draws three distinct NaN/Inf positions
    message = malformed_message(kind, RATE, 60.0, np.random.default_rng(3))
    result = validate_signal(message, CAP)
    assert isinstance(result, Rejection)
    assert result.reason is reason
    assert result.detail.startswith(detail_start)


def test_int16_pcm_published_as_float_is_named_as_such() -> None:
    message = Float32MultiArray(data=np.array([0.0, 1200.0, -32767.0], dtype=np.float32))
    assert validate_signal(message, CAP) == Rejection(
        Reason.OUT_OF_RANGE,
        "peak value 32767 is outside [-1, 1] (allowed: float32 samples in [-1, 1]; peaks below 2 are clipped); "
        "it looks like int16 PCM published as float: divide by 32768 before publishing",
    )


def test_a_peak_of_two_or_more_is_out_of_range_without_the_int16_hint_when_small() -> None:
    assert validate_signal(Float32MultiArray(data=[0.5, 2.0]), CAP) == Rejection(
        Reason.OUT_OF_RANGE,
        "peak value 2 is outside [-1, 1] (allowed: float32 samples in [-1, 1]; peaks below 2 are clipped)",
    )


def test_the_robots_int16_over_32767_and_resampling_overshoot_are_clipped_not_rejected() -> None:
    robot_block = np.array([-32768, -16384, 0, 32767], dtype=np.int16).astype(np.float32) / 32767.0
    accepted = validate_signal(Float32MultiArray(data=robot_block), CAP)
    assert isinstance(accepted, Accepted)
    assert accepted.clipped == 1
    assert accepted.samples.tolist() == [-1.0, np.float32(-16384 / 32767.0), 0.0, 1.0]
    overshoot = validate_signal(Float32MultiArray(data=[1.05, -1.999, 0.5]), CAP)
    assert isinstance(overshoot, Accepted)
    assert (overshoot.clipped, overshoot.samples.tolist()) == (2, [1.0, -1.0, 0.5])


def test_finite_huge_values_are_out_of_range_not_nan_or_inf() -> None:
    result = validate_signal(Float32MultiArray(data=[0.0, 1e300]), CAP)
    assert isinstance(result, Rejection)
    assert result.reason is Reason.OUT_OF_RANGE
    assert result.detail.startswith("peak value 1e+300 is outside [-1, 1]")


def test_valid_audio_is_accepted_as_float32_including_a_rospy_shaped_message() -> None:
    ros_like = SimpleNamespace(
        _type="std_msgs/Float32MultiArray",
        layout=SimpleNamespace(dim=[], data_offset=0),
        data=(0.25, -1.0, 1.0),
    )
    accepted = validate_signal(ros_like, CAP)
    assert isinstance(accepted, Accepted)
    assert accepted.samples.dtype == np.float32
    assert accepted.samples.tolist() == [0.25, -1.0, 1.0]
    assert accepted.clipped == 0


def test_a_layout_with_one_channel_dimension_is_mono() -> None:
    layout = MultiArrayLayout(
        dim=(MultiArrayDimension("channels", 1, 3), MultiArrayDimension("samples", 3, 3))
    )
    accepted = validate_signal(Float32MultiArray(data=[0.0, 0.1, 0.2], layout=layout), CAP)
    assert isinstance(accepted, Accepted)
    assert accepted.samples.size == 3


UNDER_TWO = float(np.nextafter(np.float32(2.0), np.float32(0.0)))  # the largest float32 below 2


@given(st.lists(st.floats(-UNDER_TWO, UNDER_TWO, width=32), min_size=1, max_size=64))
def test_samples_with_peaks_under_two_are_accepted_clipped_to_plus_minus_one_and_counted(
    values: List[float],
) -> None:
    data = np.array(values, dtype=np.float32)
    accepted = validate_signal(Float32MultiArray(data=data), CAP)
    assert isinstance(accepted, Accepted)
    assert accepted.samples.tolist() == np.clip(data, -1.0, 1.0).tolist()
    assert accepted.clipped == sum(1 for value in values if abs(value) > 1.0)


def test_a_layout_dimension_of_size_zero_is_a_count() -> None:
    accepted = validate_signal(_message([0.1, -0.2], dim=[SimpleNamespace(size=0)]), CAP)
    assert isinstance(accepted, Accepted)
    assert accepted.samples.tolist() == [np.float32(0.1), np.float32(-0.2)]


def test_a_message_of_exactly_the_largest_size_is_accepted_and_one_sample_more_is_not() -> None:
    accepted = validate_signal(Float32MultiArray(data=np.zeros(480, np.float32)), 480)
    assert isinstance(accepted, Accepted)
    assert accepted.samples.size == 480
    assert validate_signal(Float32MultiArray(data=np.zeros(481, np.float32)), 480) == Rejection(
        Reason.OVERSIZED, "481 samples in one message (allowed: at most 480, set by max_message_length)"
    )


def test_int16_samples_are_judged_by_their_value_so_minus_32768_is_not_taken_for_audio() -> None:
    # np.abs(int16(-32768)) is -32768: the peak must be taken where it cannot wrap around.
    message = _message(np.array([-32768, 0, 32767], dtype=np.int16))
    assert validate_signal(message, CAP) == Rejection(
        Reason.OUT_OF_RANGE,
        "peak value 32768 is outside [-1, 1] (allowed: float32 samples in [-1, 1]; peaks below 2 are clipped); "
        "it looks like int16 PCM published as float: divide by 32768 before publishing",
    )
    accepted = validate_signal(_message(np.array([-1, 0, 1], dtype=np.int16)), CAP)
    assert isinstance(accepted, Accepted)
    assert accepted.samples.dtype == np.float32
    assert (accepted.samples.tolist(), accepted.clipped) == ([-1.0, 0.0, 1.0], 0)


@pytest.mark.parametrize(
    ("peak", "hint"),
    [
        (255.5, ""),
        (-256.0, "; it looks like int16 PCM published as float: divide by 32768 before publishing"),
    ],
)
def test_the_int16_hint_starts_at_a_peak_of_256(peak: float, hint: str) -> None:
    assert validate_signal(Float32MultiArray(data=[0.5, peak]), CAP) == Rejection(
        Reason.OUT_OF_RANGE,
        f"peak value {abs(peak):g} is outside [-1, 1] (allowed: float32 samples in [-1, 1]; "
        f"peaks below 2 are clipped){hint}",
    )


def _generator() -> object:
    return (x for x in [0.1, 0.2])


@pytest.mark.parametrize(
    ("message", "detail"),
    [
        (_message(0.5), "data is float (allowed: a flat sequence of float32 samples)"),
        (_message(np.float32(0.5)), "data is float32 (allowed: a flat sequence of float32 samples)"),
        (
            _message(np.zeros((2, 3), np.float32)),
            "data is 2-D, shape (2, 3) (allowed: a flat sequence of float32 samples)",
        ),
        (_message(np.array(0.5)), "data is a scalar (allowed: a flat sequence of float32 samples)"),
        (
            _message([[0.1, 0.2], [0.3, 0.4]]),
            "data is 2-D, shape (2, 2) (allowed: a flat sequence of float32 samples)",
        ),
        (
            _message([[0.1], [0.2, 0.3]]),
            "data is a ragged nested list (allowed: a flat sequence of float32 samples)",
        ),
        (_message("0.1 0.2"), "data is str (allowed: a flat sequence of float32 samples)"),
        (_message(b"\x00\x00"), "data is bytes (allowed: a flat sequence of float32 samples)"),
        (_message({"a": 0.1}), "data is dict (allowed: a flat sequence of float32 samples)"),
        (_message(_generator()), "data is generator (allowed: a flat sequence of float32 samples)"),
        (_message(None), "data is NoneType (allowed: a flat sequence of float32 samples)"),
        (
            _message(np.array([0.1, None], dtype=object)),
            "data holds object values (allowed: a flat sequence of float32 samples)",
        ),
        (_message(["0.1", "0.2"]), "data holds <U3 values (allowed: a flat sequence of float32 samples)"),
        (_message([True, False]), "data holds bool values (allowed: a flat sequence of float32 samples)"),
        (
            SimpleNamespace(_type="std_msgs/Float32MultiArray", layout=SimpleNamespace(dim=[])),
            "data is NoneType (allowed: a flat sequence of float32 samples)",
        ),
        (
            SimpleNamespace(_type="std_msgs/Float32MultiArray", data=[0.1]),
            "layout.dim is NoneType, not a list (allowed: a layout with a list of dimensions)",
        ),
        (
            _message([0.1], dim=None),
            "layout.dim is NoneType, not a list (allowed: a layout with a list of dimensions)",
        ),
        (
            _message([0.1], dim=[SimpleNamespace(size=-1)]),
            "layout dimension size -1 is not a count (allowed: sizes 0 or more)",
        ),
        (
            _message([0.1], dim=[SimpleNamespace(size="2")]),
            "layout dimension size '2' is not a count (allowed: sizes 0 or more)",
        ),
        (
            _message([0.1], dim=[SimpleNamespace(size=True)]),
            "layout dimension size True is not a count (allowed: sizes 0 or more)",
        ),
        (
            _message([0.1], dim=[SimpleNamespace(label="samples")]),
            "layout dimension size None is not a count (allowed: sizes 0 or more)",
        ),
        (
            _message([0.1], dim=4),
            "layout.dim is int, not a list (allowed: a layout with a list of dimensions)",
        ),
    ],
)
def test_data_that_is_not_a_flat_sequence_of_numbers_is_rejected_naming_what_it_is(
    message: object, detail: str
) -> None:
    assert validate_signal(message, CAP) == Rejection(Reason.MALFORMED, detail)


def test_warnings_are_counted_per_reason_and_rate_limited(caplog: pytest.LogCaptureFixture) -> None:
    now = [0.0]
    log = RejectionLog(lambda: now[0], "/soundDetection/signal", interval=10.0)
    nan = Rejection(Reason.NON_FINITE, "1 of 2 samples are NaN or Inf")
    empty = Rejection(Reason.EMPTY, "empty data")
    with caplog.at_level(logging.WARNING, logger="speech_event"):
        for step in range(5):
            now[0] = step * 1.0
            log.record(nan)
        log.record(empty)
        now[0] = 12.0
        log.record(nan)
    assert [record.getMessage() for record in caplog.records] == [
        "rejected a message on /soundDetection/signal: 1 of 2 samples are NaN or Inf",
        "rejected a message on /soundDetection/signal: empty data",
        "rejected a message on /soundDetection/signal: 1 of 2 samples are NaN or Inf"
        " (4 more like it since the last warning)",
    ]
    assert log.counts[Reason.NON_FINITE] == 6
    assert log.counts[Reason.EMPTY] == 1
    assert log.counts[Reason.OVERSIZED] == 0
