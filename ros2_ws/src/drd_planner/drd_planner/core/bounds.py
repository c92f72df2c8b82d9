"""The verification lower bound (docs/algorithms.md, "Bounds and exact optima"), cheap for any size.

:func:`oracle_lower_bound` (8.1) gives per world the cost of its cheapest valid library path: no policy
that proves a path free can pay less. The exact, exponential optima that measure how far the greedy
policies are from the Bayes-optimal one on tiny instances live in :mod:`drd_planner.bench.optima`
(finite database) and :mod:`drd_planner.bench.optima_bernoulli` (independent edges).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray
from drd_planner.exceptions import ProblemError

__all__ = ["bool_matrix", "oracle_lower_bound"]


def bool_matrix(name: str, a: npt.ArrayLike) -> BoolArray:
    """``a`` as a 2-D bool array; ProblemError (naming it ``name``) unless 2-D and only 0/1 or bool."""
    arr = np.asarray(a)
    if arr.ndim != 2:
        raise ProblemError(f"{name} must be a 2-D array, got shape {arr.shape}")
    if arr.dtype != np.bool_ and arr.size and not np.all((arr == 0) | (arr == 1)):
        raise ProblemError(f"{name} must hold only 0/1 (or bool) values")
    return np.asarray(arr, dtype=bool)


def oracle_lower_bound(R: npt.ArrayLike, path_costs: npt.ArrayLike) -> FloatArray:
    """Per world the cost of its cheapest valid library path (the verification bound, 8.1).

    Any policy that ends an episode by proving a path free has checked every edge of that path,
    so its cost on world h is at least this value; the prior-weighted mean over worlds bounds
    every policy's expected cost from below.

    Args:
        R: (k, m) bool, R[h, i] = path i is valid in world h.
        path_costs: (m,) float, the cost of checking every edge of each path.

    Returns:
        (k,) float64 cheapest valid path cost per world; NaN for worlds with no valid path.
    """
    r = bool_matrix("R", R)
    costs = np.asarray(path_costs, dtype=np.float64)
    if costs.shape != (r.shape[1],):
        raise ProblemError(f"path_costs must have shape ({r.shape[1]},), got {costs.shape}")
    if not np.all(np.isfinite(costs)) or np.any(costs < 0):
        raise ProblemError("path_costs must be finite and non-negative")
    if r.shape[1] == 0:
        return np.full(r.shape[0], np.nan)
    best = np.where(r, costs[None, :], np.inf).min(axis=1)
    return np.asarray(np.where(np.isfinite(best), best, np.nan), dtype=np.float64)
