"""Bisection order of samples along a trajectory, so blocked edges are found after few checks.

Collisions are spatially coherent: checking the middle sample first, then the middles of both halves, and so
on (breadth first), finds an obstacle that covers any stretch of the trajectory sooner than a sweep from one
end would.
"""

from __future__ import annotations

from collections import deque
from functools import lru_cache

import numpy as np

from drd_planner.arrays import IntArray
from drd_planner.exceptions import GeometryError

__all__ = ["bisection_order", "bisection_rank"]


@lru_cache(maxsize=256)
def bisection_order(n: int) -> IntArray:
    """(n,) read-only permutation of ``range(n)``: the middle index, then the middles of each half, breadth first.

    Example: n = 7 gives [3, 1, 5, 0, 2, 4, 6].
    """
    if int(n) != n or n < 0:
        raise GeometryError(f"bisection order needs a count >= 0, got {n!r}")
    order: list[int] = []
    intervals: deque[tuple[int, int]] = deque([(0, int(n) - 1)])
    while intervals:
        lo, hi = intervals.popleft()
        if lo > hi:
            continue
        mid = (lo + hi) // 2
        order.append(mid)
        intervals.append((lo, mid - 1))
        intervals.append((mid + 1, hi))
    result = np.array(order, dtype=np.int64)
    result.flags.writeable = False
    return result


@lru_cache(maxsize=256)
def bisection_rank(n: int) -> IntArray:
    """(n,) read-only position of each index in :func:`bisection_order` (the inverse permutation)."""
    rank = np.empty(n, dtype=np.int64)
    rank[bisection_order(n)] = np.arange(n, dtype=np.int64)
    rank.flags.writeable = False
    return rank
