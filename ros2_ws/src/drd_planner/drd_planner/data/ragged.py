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


def pack_ragged(
    parts: Sequence[npt.NDArray[Any] | tuple[float, ...]], dtype: npt.DTypeLike
) -> tuple[npt.NDArray[Any], IntArray]:
    """``(flat, offsets)``: the parts concatenated along axis 0 (as ``dtype``) and (len(parts) + 1,) int64 offsets.

    Part j is ``flat[offsets[j]:offsets[j + 1]]``; no parts give an empty 1-D ``flat`` and ``offsets == [0]``.
    """
    offsets = np.concatenate([[0], np.cumsum([len(p) for p in parts])]).astype(np.int64)
    if not parts:
        return np.empty(0, dtype=dtype), offsets
    return np.concatenate(parts).astype(dtype), offsets


def unpack_ragged(
    flat: npt.NDArray[Any], offsets: IntArray, count: int | None, what: str, error: type[DrdError]
) -> tuple[npt.NDArray[Any], ...]:
    """The parts of ``flat`` (views): ``count`` of them, or at least one when ``count`` is None.

    Raises:
        error: the offsets do not partition ``flat`` into that many parts (the message names ``what``).
    """
    parts = offsets.shape[0] - 1 if offsets.ndim == 1 else -1
    if (
        (parts < 1 if count is None else offsets.shape != (count + 1,))
        or offsets[0] != 0
        or offsets[-1] != flat.shape[0]
        or np.any(np.diff(offsets) < 0)
    ):
        wanted = "parts" if count is None else f"{count} parts"
        raise error(f"{what} offsets do not partition the concatenated array into {wanted}")
    return tuple(flat[a:b] for a, b in itertools.pairwise(offsets.tolist()))
