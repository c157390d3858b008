"""Step 1 of the pipeline: decide whether a message on /soundDetection/signal is usable audio.

A message is either accepted (mono float32 samples in [-1, 1]) or rejected whole with a reason
and a sentence that names the problem and what is allowed.
"""

import enum
from dataclasses import dataclass
from typing import Union

import numpy as np

from speech_event.messages import Float32MultiArray, message_type_name


class Reason(enum.Enum):
    EMPTY = "empty"
    NON_FINITE = "nan_or_inf"
    OUT_OF_RANGE = "out_of_range"
    MULTI_DIMENSIONAL = "multi_dimensional"
    OVERSIZED = "oversized"
    WRONG_TYPE = "wrong_type"


@dataclass(frozen=True)
class Rejection:
    reason: Reason
    detail: str


# Peaks this large in a "float" message are what int16 samples look like when not divided by 32768.
_INT16_LIKE_PEAK = 2.0


def validate_signal(message: object, max_samples: int) -> Union[np.ndarray, Rejection]:
    """The message's samples as a float32 array, or why it cannot be used."""
    expected_type = Float32MultiArray._type
    if message_type_name(message) != expected_type:
        return Rejection(
            Reason.WRONG_TYPE,
            f"message of type {message_type_name(message)} "
            f"(allowed: {expected_type} with mono float32 samples)",
        )
    sizes = [dimension.size for dimension in message.layout.dim]  # type: ignore[attr-defined]
    if sum(1 for size in sizes if size > 1) > 1:
        return Rejection(
            Reason.MULTI_DIMENSIONAL,
            "layout has dimensions {} (allowed: mono audio, an empty layout or one dimension)".format(
                " x ".join(str(size) for size in sizes)
            ),
        )
    samples = np.asarray(message.data, dtype=np.float32)  # type: ignore[attr-defined]
    if samples.size == 0:
        return Rejection(Reason.EMPTY, "empty data (allowed: 1 or more float32 samples)")
    if samples.size > max_samples:
        return Rejection(
            Reason.OVERSIZED,
            f"{samples.size} samples in one message "
            f"(allowed: at most {max_samples}, set by max_message_length)",
        )
    peak = float(np.max(np.abs(samples)))  # NaN propagates, so one pass finds both problems
    if not np.isfinite(peak):
        bad = int(np.count_nonzero(~np.isfinite(samples)))
        return Rejection(
            Reason.NON_FINITE,
            f"{bad} of {samples.size} samples are NaN or Inf (allowed: finite values in [-1, 1])",
        )
    if peak > 1.0:
        hint = (
            "; it looks like int16 PCM published as float: divide by 32768 before publishing"
            if peak >= _INT16_LIKE_PEAK
            else ""
        )
        return Rejection(
            Reason.OUT_OF_RANGE,
            f"peak value {peak:g} is outside [-1, 1] (allowed: float32 samples in [-1, 1]){hint}",
        )
    return samples
