"""Plain-Python messages shaped like the std_msgs types the node speaks.

Their attribute names match rospy's generated classes (``layout.dim``, ``data``, ``_type``),
so the node's logic reads a rospy message and one of these the same way.
"""

from dataclasses import dataclass, field
from typing import ClassVar, Sequence, Tuple, Union

import numpy as np


@dataclass(frozen=True)
class MultiArrayDimension:
    label: str = ""
    size: int = 0
    stride: int = 0


@dataclass(frozen=True)
class MultiArrayLayout:
    dim: Tuple[MultiArrayDimension, ...] = ()
    data_offset: int = 0


@dataclass
class Float32MultiArray:
    """What soundDetection publishes: mono float32 samples, layout left empty."""

    _type: ClassVar[str] = "std_msgs/Float32MultiArray"
    data: Union[np.ndarray, Sequence[float]] = ()
    layout: MultiArrayLayout = field(default_factory=MultiArrayLayout)


@dataclass
class String:
    """What the node publishes on /speechEvent/text."""

    _type: ClassVar[str] = "std_msgs/String"
    data: str = ""


def message_type_name(message: object) -> str:
    """The ROS type name of a message, or its Python class name when it has none."""
    return str(getattr(message, "_type", type(message).__name__))
