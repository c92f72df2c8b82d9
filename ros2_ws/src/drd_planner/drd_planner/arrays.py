"""Array type aliases shared by every module: one place instead of one per module."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

__all__ = ["BoolArray", "FloatArray", "IntArray"]

FloatArray = npt.NDArray[np.float64]
"""Float64 array (lengths in metres, angles in radians unless a docstring says otherwise)."""
IntArray = npt.NDArray[np.int64]
"""Int64 array (indices, counts)."""
BoolArray = npt.NDArray[np.bool_]
"""Boolean array (masks, edge outcomes: True = free)."""
