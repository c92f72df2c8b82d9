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
        for i, p in enumerate(paths):
            if p.size == 0:
                raise ProblemError(f"library path {i} has no edges")
            if p.min() < 0 or p.max() >= self.num_edges:
                raise ProblemError(f"library path {i} names an edge outside [0, {self.num_edges})")
            if np.unique(p).size != p.size:
                raise ProblemError(f"library path {i} uses an edge twice")
        object.__setattr__(self, "path_edges", paths)
        rows = np.repeat(np.arange(len(paths)), [p.size for p in paths])
        cols = np.concatenate(paths)
        data = np.ones(cols.size, dtype=np.float64)
        csr = sp.csr_array((data, (rows, cols)), shape=(len(paths), self.num_edges))
        csr.sort_indices()
        object.__setattr__(self, "_csr", csr)
        csc = csr.tocsc()
        csc.sort_indices()
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
