"""Path libraries and their path x edge incidence."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp

from drd_planner.arrays import BoolArray, IntArray
from drd_planner.exceptions import ProblemError


@dataclass(frozen=True)
class PathLibrary:
    """A library of m candidate paths, each a set of edge (test) ids.

    Attributes:
        path_edges: m arrays of edge ids in traversal order (a path's edges are distinct).
        num_edges: E, the number of tests in the underlying graph.
        vertex_paths: optionally, m vertex sequences (start first, goal last).
    """

    path_edges: tuple[IntArray, ...]
    num_edges: int
    vertex_paths: tuple[IntArray, ...] | None = None
    _csr: sp.csr_array = field(init=False, repr=False, compare=False)
    _csc: sp.csc_array = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        paths = tuple(np.asarray(p, dtype=np.int64).ravel() for p in self.path_edges)
        if not paths:
            raise ProblemError("a path library needs at least one path")
        sizes = np.array([p.size for p in paths], dtype=np.int64)
        if (sizes == 0).any():
            raise ProblemError(f"library path {int(np.argmax(sizes == 0))} has no edges")
        rows = np.repeat(np.arange(len(paths)), sizes)
        cols = np.concatenate(paths)
        outside = (cols < 0) | (cols >= self.num_edges)
        if outside.any():
            raise ProblemError(
                f"library path {int(rows[np.argmax(outside)])} names an edge outside [0, {self.num_edges})"
            )
        # Both incidences built directly in their sorted order (a path's edges, a column's paths).
        by_row = np.lexsort((cols, rows))
        repeated = np.flatnonzero((np.diff(rows[by_row]) == 0) & (np.diff(cols[by_row]) == 0))
        if repeated.size:
            raise ProblemError(f"library path {int(rows[by_row][repeated[0]])} uses an edge twice")
        object.__setattr__(self, "path_edges", paths)
        shape = (len(paths), self.num_edges)
        csr_indptr = np.concatenate([[0], np.cumsum(sizes)])
        csr = sp.csr_array((np.ones(cols.size), cols[by_row], csr_indptr), shape=shape)
        object.__setattr__(self, "_csr", csr)
        by_col = np.lexsort((rows, cols))
        csc_indptr = np.concatenate([[0], np.cumsum(np.bincount(cols, minlength=self.num_edges))])
        csc = sp.csc_array((np.ones(cols.size), rows[by_col], csc_indptr), shape=shape)
        object.__setattr__(self, "_csc", csc)

    @classmethod
    def from_sequences(cls, paths: Sequence[Sequence[int]], num_edges: int) -> PathLibrary:
        """Build from plain sequences of edge ids."""
        return cls(tuple(np.asarray(p, dtype=np.int64) for p in paths), num_edges)

    @property
    def num_paths(self) -> int:
        """M."""
        return len(self.path_edges)

    @property
    def incidence(self) -> sp.csr_array:
        """(m, E) float64 sparse path x edge incidence B (1 where the path uses the edge)."""
        return self._csr

    @property
    def incidence_csc(self) -> sp.csc_array:
        """The same incidence in CSC form: column e lists the paths through edge e."""
        return self._csc

    def dense_incidence(self) -> BoolArray:
        """(m, E) bool dense incidence (small problems only)."""
        return np.asarray(self._csr.toarray(), dtype=bool)

    def paths_through(self, edge: int) -> IntArray:
        """Sorted ids of the paths that use ``edge``."""
        csc = self._csc
        return np.asarray(csc.indices[csc.indptr[edge] : csc.indptr[edge + 1]], dtype=np.int64)

    @property
    def library_edges(self) -> IntArray:
        """Sorted ids of the edges used by at least one path."""
        return np.flatnonzero(np.diff(self._csc.indptr) > 0).astype(np.int64)

    def path_costs(self, edge_costs: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """(m,) cost of checking every edge of each path."""
        return np.asarray(self._csr @ np.asarray(edge_costs, dtype=np.float64), dtype=np.float64)

    def valid_paths(self, x: npt.ArrayLike) -> BoolArray:
        """R for worlds ``x`` (n, E) or (E,) bool: (n, m) or (m,) bool, path valid iff all its edges are."""
        xb = np.asarray(x, dtype=bool)
        lib = self.library_edges  # only the library's own columns matter (X may span a large graph)
        blocked = (~xb[..., lib]).astype(np.float32)
        counts = self._csr[:, lib] @ blocked.T
        valid: BoolArray = np.asarray(counts == 0, dtype=bool).T
        return valid
