"""Step 1 of the pipeline: decide whether a message on /soundDetection/signal is usable audio.

Any object a transport can deliver is either accepted as mono float32 samples in [-1, 1] or
rejected whole with a reason and a sentence that names the problem and what is allowed. Nothing in
here raises: a hostile in-process publisher can hand over anything at all.

Samples a hair outside [-1, 1] are clipped, not rejected: the robot's soundDetection divides int16
by 32767 (so -32768 becomes -1.00003) and resampled full-scale audio overshoots to about 1.05.
Peaks of 2.0 and above are no such overshoot (int16 PCM not divided, for one) and are rejected.
"""

import enum
from dataclasses import dataclass
from typing import Union

import numpy as np

from speech_event.messages import Float32MultiArray, message_type_name


class Reason(enum.Enum):
    """Why a message on /soundDetection/signal was rejected; the value names it in /diagnostics."""

    EMPTY = "empty"
    NON_FINITE = "nan_or_inf"
    OUT_OF_RANGE = "out_of_range"
    MULTI_DIMENSIONAL = "multi_dimensional"
    OVERSIZED = "oversized"
    WRONG_TYPE = "wrong_type"
    MALFORMED = "malformed"


@dataclass(frozen=True)
class Rejection:
    """A rejected message: the reason, and a sentence naming the problem and what is allowed."""

    reason: Reason
    detail: str


@dataclass(frozen=True)
class Accepted:
    """An accepted message's samples, and how many were clipped into [-1, 1]."""

    samples: np.ndarray  # mono float32 in [-1, 1]
    clipped: int = 0  # samples that were a hair outside [-1, 1] and were clipped


# Peaks below this are an overshoot to clip; from here on they are not audio in [-1, 1].
CLIP_LIMIT = 2.0
# Peaks this large in a "float" message are what int16 samples look like when not divided by 32768.
_INT16_LIKE_PEAK = 256.0
_FLAT = "allowed: a flat sequence of float32 samples"


def _dimension_sizes(message: object) -> Union[list, Rejection]:  # type: ignore[type-arg]
    dims = getattr(getattr(message, "layout", None), "dim", None)
    if not isinstance(dims, (list, tuple)):
        return Rejection(
            Reason.MALFORMED,
            f"layout.dim is {type(dims).__name__}, not a list (allowed: a layout with a list of dimensions)",
        )
    sizes = [getattr(dimension, "size", None) for dimension in dims]
    bad = [size for size in sizes if isinstance(size, bool) or not isinstance(size, (int, np.integer))]
    if bad or any(size < 0 for size in sizes):  # type: ignore[operator]
        return Rejection(
            Reason.MALFORMED,
            f"layout dimension size {(bad or sizes)[0]!r} is not a count (allowed: sizes 0 or more)",
        )
    return sizes


def _array(data: object) -> Union[np.ndarray, Rejection]:
    """``data`` as a 1-D numeric array, or why it is not one."""
    if isinstance(data, np.ndarray):
        array = data
    elif isinstance(data, (list, tuple)):
        try:
            array = np.asarray(data)
        except (ValueError, TypeError):  # ragged nesting
            return Rejection(Reason.MALFORMED, f"data is a ragged nested list ({_FLAT})")
    else:
        return Rejection(Reason.MALFORMED, f"data is {type(data).__name__} ({_FLAT})")
    if array.ndim != 1:
        shape = "a scalar" if array.ndim == 0 else f"{array.ndim}-D, shape {array.shape}"
        return Rejection(Reason.MALFORMED, f"data is {shape} ({_FLAT})")
    if array.dtype.kind not in "fiu":
        return Rejection(Reason.MALFORMED, f"data holds {array.dtype} values ({_FLAT})")
    return array


def validate_signal(message: object, max_samples: int) -> Union[Accepted, Rejection]:
    """The message's samples as float32 in [-1, 1], or why it cannot be used."""
    expected_type = Float32MultiArray._type
    if message_type_name(message) != expected_type:
        return Rejection(
            Reason.WRONG_TYPE,
            f"message of type {message_type_name(message)} "
            f"(allowed: {expected_type} with mono float32 samples)",
        )
    sizes = _dimension_sizes(message)
    if isinstance(sizes, Rejection):
        return sizes
    if sum(1 for size in sizes if size > 1) > 1:
        return Rejection(
            Reason.MULTI_DIMENSIONAL,
            "layout has dimensions {} (allowed: mono audio, an empty layout or one dimension)".format(
                " x ".join(str(size) for size in sizes)
            ),
        )
    array = _array(getattr(message, "data", None))
    if isinstance(array, Rejection):
        return array
    if array.size == 0:
        return Rejection(Reason.EMPTY, "empty data (allowed: 1 or more float32 samples)")
    if array.size > max_samples:
        return Rejection(
            Reason.OVERSIZED,
            f"{array.size} samples in one message "
            f"(allowed: at most {max_samples}, set by max_message_length)",
        )
    # Checked at the data's own precision, so a finite 1e300 is out of range, not Inf in float32.
    wide = array if array.dtype == np.float32 else array.astype(np.float64)
    peak = float(np.max(np.abs(wide)))  # NaN propagates, so one pass finds both problems
    if not np.isfinite(peak):
        bad = int(np.count_nonzero(~np.isfinite(wide)))
        return Rejection(
            Reason.NON_FINITE,
            f"{bad} of {array.size} samples are NaN or Inf (allowed: finite values in [-1, 1])",
        )
    if peak >= CLIP_LIMIT:
        hint = (
            "; it looks like int16 PCM published as float: divide by 32768 before publishing"
            if peak >= _INT16_LIKE_PEAK
            else ""
        )
        return Rejection(
            Reason.OUT_OF_RANGE,
            f"peak value {peak:g} is outside [-1, 1] (allowed: float32 samples in [-1, 1]; "
            f"peaks below {CLIP_LIMIT:g} are clipped){hint}",
        )
    samples = array.astype(np.float32, copy=False)
    if peak <= 1.0:
        return Accepted(samples)
    return Accepted(np.clip(samples, -1.0, 1.0), int(np.count_nonzero(np.abs(wide) > 1.0)))
