"""Array type aliases shared by every module, and the distinct rows of a matrix: one place, not one per module."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

__all__ = ["BoolArray", "FloatArray", "IntArray", "first_distinct_rows", "row_groups", "unique_bool_rows"]

FloatArray = npt.NDArray[np.float64]
"""Float64 array (lengths in metres, angles in radians unless a docstring says otherwise)."""
IntArray = npt.NDArray[np.int64]
"""Int64 array (indices, counts)."""
BoolArray = npt.NDArray[np.bool_]
"""Boolean array (masks, edge outcomes: True = free)."""


def unique_bool_rows(rows: npt.ArrayLike) -> tuple[BoolArray, IntArray]:
    """The distinct rows of a (n, k) bool matrix and the (n,) index of each row among them.

    The same answer as ``np.unique(rows, axis=0, return_inverse=True)`` (rows in lexicographic order, False
    before True), computed on the rows packed into bytes: about 40x faster on (900, 500) matrices, where
    ``np.unique`` compares structured rows element by element.
    """
    a = np.asarray(rows, dtype=bool)
    if a.ndim != 2:
        raise ValueError(f"unique_bool_rows needs a (n, k) matrix, got shape {a.shape}")
    if a.shape[0] == 0 or a.shape[1] == 0:
        distinct, inverse = np.unique(a, axis=0, return_inverse=True)
        return distinct.astype(bool), np.asarray(inverse, dtype=np.int64).ravel()
    packed = np.ascontiguousarray(np.packbits(a, axis=1))  # big-endian bits: byte order is row order
    keys = packed.view(np.dtype((np.void, packed.shape[1]))).ravel()
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    return a[first], np.asarray(inverse, dtype=np.int64).ravel()


def row_groups(rows: npt.ArrayLike) -> tuple[IntArray, IntArray]:
    """The rows of a (n, k) matrix grouped by equality: (d,) first rows, (n,) each row's group.

    The first array holds, ascending, the index of each distinct row's first occurrence; the group of a row
    is an index into it (groups numbered in order of their first row). Rows are compared as raw bytes (a bool
    matrix's packed into bits first: 3 ms for the 1 800 x 3 012 worlds of ``heli_wires``).
    """
    a = np.asarray(rows)
    if a.ndim != 2:
        raise ValueError(f"row_groups needs a (n, k) matrix, got shape {a.shape}")
    n = a.shape[0]
    if n == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    if a.shape[1] == 0:
        return np.zeros(1, dtype=np.int64), np.zeros(n, dtype=np.int64)
    if a.dtype == np.bool_:
        a = np.packbits(a, axis=1)
    a = np.ascontiguousarray(a)
    keys = a.view(np.dtype((np.void, a.shape[1] * a.dtype.itemsize))).ravel()
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")  # the groups renumbered in order of their first row
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    return first[order].astype(np.int64), rank[np.asarray(inverse).ravel()].astype(np.int64)


def first_distinct_rows(rows: npt.ArrayLike) -> IntArray:
    """(d,) ascending indices of the first occurrence of each distinct row of a (n, k) matrix.

    The set ``np.unique(rows, axis=0, return_index=True)`` gives, sorted (:func:`row_groups`).
    """
    return row_groups(rows)[0]
