"""Shared pieces of the exact optima (:mod:`drd_planner.bench.optima`, :mod:`~drd_planner.bench.optima_bernoulli`).

Input validation (every failure a :class:`~drd_planner.exceptions.ProblemError`), the size limits the
exponential solvers accept, and bitmask helpers: sets of worlds and sets of edges are Python ``int``
bitmasks (bit j set = member j), which makes memo keys hashable and set operations cheap.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray
from drd_planner.core.library import PathLibrary
from drd_planner.exceptions import ProblemError

__all__ = [
    "MAX_DRD_WORLDS",
    "MAX_EPISODE_WORLDS",
    "MAX_LIBRARY_EDGES",
    "MAX_POLICY_NODES",
    "EdgeSelector",
    "PathsLike",
    "SelectorFactory",
    "WorldMass",
    "bits",
    "check_costs",
    "check_library",
    "check_prior",
    "check_theta",
    "column_masks",
    "local_path_masks",
    "path_library",
]

#: Library paths: per path its edge ids, as a sequence of ints or an integer array.
PathsLike = Sequence[Sequence[int] | npt.NDArray[np.integer[Any]]]

#: Largest database :func:`~drd_planner.bench.optima.exact_drd_optimum` accepts (version spaces are
#: subsets of the worlds).
MAX_DRD_WORLDS = 24
#: Largest database :func:`~drd_planner.bench.optima.exact_episode_optimum` accepts.
MAX_EPISODE_WORLDS = 16
#: Most library edges (edges on at least one path) the episode DPs and policy evaluation accept.
MAX_LIBRARY_EDGES = 16
#: Default limit on the number of decision-tree nodes
#: :func:`~drd_planner.bench.optima_bernoulli.expected_policy_cost_bernoulli` visits.
MAX_POLICY_NODES = 1_000_000


class EdgeSelector(Protocol):
    """Anything with a ``select`` method, e.g. :class:`drd_planner.core.bisect.Bisect`."""

    def select(self) -> int | None:
        """The next edge to check, or None when the policy stops."""
        ...


#: Builds a fresh selector that has already heard ``observations`` (edge -> free).
SelectorFactory = Callable[[dict[int, bool]], EdgeSelector]


# --------------------------------------------------------------------------------------------------
# input validation
# --------------------------------------------------------------------------------------------------


def check_costs(edge_costs: npt.ArrayLike, num_edges: int) -> FloatArray:
    """(E,) float64 costs; ProblemError unless of shape (num_edges,), finite and positive."""
    costs = np.asarray(edge_costs, dtype=np.float64)
    if costs.shape != (num_edges,):
        raise ProblemError(f"edge_costs must have shape ({num_edges},), got {costs.shape}")
    if not np.all(np.isfinite(costs)) or np.any(costs <= 0):
        raise ProblemError("edge_costs must be finite and positive")
    return costs


def check_prior(prior: npt.ArrayLike | None, n: int) -> FloatArray:
    """(n,) float64 prior weights (ones for None); ProblemError unless finite, >= 0, positive sum."""
    if prior is None:
        return np.ones(n)
    w = np.asarray(prior, dtype=np.float64)
    if w.shape != (n,):
        raise ProblemError(f"prior must have shape ({n},), got {w.shape}")
    if not np.all(np.isfinite(w)) or np.any(w < 0) or not w.sum() > 0:
        raise ProblemError("prior must be finite, non-negative and have a positive sum")
    return w


def check_theta(theta: npt.ArrayLike) -> FloatArray:
    """(E,) float64 edge probabilities; ProblemError unless 1-D and in [0, 1]."""
    th = np.asarray(theta, dtype=np.float64)
    if th.ndim != 1:
        raise ProblemError(f"theta must be a 1-D array, got shape {th.shape}")
    if not np.all((th >= 0) & (th <= 1)):
        raise ProblemError("theta must hold probabilities in [0, 1]")
    return th


def path_library(paths: PathsLike, num_edges: int) -> PathLibrary:
    """A PathLibrary from ``paths`` (raises ProblemError for non-integer ids and bad paths)."""
    lists: list[list[int]] = []
    for i, p in enumerate(paths):
        arr = np.asarray(p).ravel()
        if arr.size and not np.issubdtype(arr.dtype, np.integer):
            raise ProblemError(f"library path {i} must list integer edge ids, got dtype {arr.dtype}")
        lists.append([int(e) for e in arr.tolist()])
    return PathLibrary.from_sequences(lists, num_edges)


def check_library(paths: PathsLike, num_edges: int) -> PathLibrary:
    """Validate ``paths`` (raises ProblemError) and refuse more than MAX_LIBRARY_EDGES library edges."""
    library = path_library(paths, num_edges)
    k = library.library_edges.size
    if k > MAX_LIBRARY_EDGES:
        raise ProblemError(f"the library uses {k} distinct edges; exact evaluation is limited to {MAX_LIBRARY_EDGES}")
    return library


# --------------------------------------------------------------------------------------------------
# bitmasks
# --------------------------------------------------------------------------------------------------


def local_path_masks(library: PathLibrary) -> tuple[list[int], list[int]]:
    """(library edge ids in increasing order, per path the bitmask of its local edge indices)."""
    edges = [int(e) for e in library.library_edges]
    local = {e: j for j, e in enumerate(edges)}
    masks = [sum(1 << local[int(e)] for e in p) for p in library.path_edges]
    return edges, masks


class WorldMass:
    """Prior mass of a bitmask of worlds by byte-wise lookup tables (exact for integer weights)."""

    def __init__(self, weights: FloatArray) -> None:
        """Tables for (n,) non-negative ``weights``."""
        self._tables: list[list[float]] = []
        for start in range(0, weights.size, 8):
            chunk = [float(v) for v in weights[start : start + 8]]
            table = [0.0] * 256
            for byte in range(1, 256):
                low = (byte & -byte).bit_length() - 1
                table[byte] = table[byte & (byte - 1)] + (chunk[low] if low < len(chunk) else 0.0)
            self._tables.append(table)

    def __call__(self, mask: int) -> float:
        """Sum of the weights of the worlds whose bit is set in ``mask``."""
        total = 0.0
        for table in self._tables:
            total += table[mask & 255]
            mask >>= 8
        return total


def bits(mask: int) -> list[int]:
    """Indices of the set bits of ``mask``, increasing."""
    out = []
    while mask:
        low = mask & -mask
        out.append(low.bit_length() - 1)
        mask ^= low
    return out


def column_masks(x: BoolArray) -> list[int]:
    """Per column of (n, E) ``x`` the bitmask of the rows where it is True."""
    weights = [1 << h for h in range(x.shape[0])]
    return [sum(w for w, v in zip(weights, col, strict=True) if v) for col in x.T.tolist()]
