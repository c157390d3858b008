"""Hypothesis strategies for audio, block splits and texts."""

from typing import List

import numpy as np
from hypothesis import strategies as st

TONES_TEXT = st.text(alphabet="abcdefghijklmnopqrstuvwxyz' ", max_size=200)


@st.composite
def audio(draw: st.DrawFn, max_samples: int) -> np.ndarray:
    """Mono float32 audio: loud stretches and quiet ones, so a quietest point exists."""
    size = draw(st.integers(1, max_samples))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    envelope = np.repeat(rng.uniform(0.0, 1.0, size // 400 + 1), 400)[:size]
    return (rng.uniform(-1.0, 1.0, size) * envelope).astype(np.float32)


@st.composite
def split_points(draw: st.DrawFn, size: int) -> List[int]:
    """Where to cut ``size`` samples into blocks: sorted, inside (0, size)."""
    if size < 2:
        return []
    return sorted(draw(st.sets(st.integers(1, size - 1), max_size=12)))


def split(samples: np.ndarray, points: List[int]) -> List[np.ndarray]:
    return [block for block in np.split(samples, points) if block.size]
