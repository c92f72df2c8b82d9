"""Ragged arrays (one row block per item) stored as one concatenated array plus offsets."""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import IntArray
from drd_planner.exceptions import DrdError

__all__ = ["pack_ragged", "unpack_ragged"]


def pack_ragged(parts: Sequence[npt.NDArray[Any]], dtype: npt.DTypeLike) -> tuple[npt.NDArray[Any], IntArray]:
    """``(flat, offsets)``: the parts concatenated (as ``dtype``) and (len(parts) + 1,) int64 offsets."""
    offsets = np.concatenate([[0], np.cumsum([len(p) for p in parts])]).astype(np.int64)
    return np.concatenate(parts).astype(dtype), offsets


def unpack_ragged(
    flat: npt.NDArray[Any], offsets: IntArray, count: int, what: str, error: type[DrdError]
) -> tuple[npt.NDArray[Any], ...]:
    """The ``count`` parts of ``flat`` (views); ``error`` names ``what`` unless the offsets partition it."""
    if (
        offsets.shape != (count + 1,)
        or offsets[0] != 0
        or offsets[-1] != flat.shape[0]
        or np.any(np.diff(offsets) < 0)
    ):
        raise error(f"{what} offsets do not partition the concatenated array into {count} parts")
    return tuple(flat[a:b] for a, b in itertools.pairwise(offsets.tolist()))
