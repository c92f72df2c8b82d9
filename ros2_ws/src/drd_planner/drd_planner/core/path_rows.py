"""A path library as a padded table of library-local edge indices: per-path work on any subset of paths.

BiSECt's state and the region rule keep per-path quantities that each outcome changes for some paths
only (which edges an alive path still has, its expected proof cost). :class:`PathRows` stores the
library as an (L, m) table, column i holding path i's edges as indices into the library's K edges and
padded with K, the index of a neutral slot; gathering a per-edge vector of K + 1 values through the
columns of some paths gives an (L, r) block with one path per column, which ``numpy`` then reduces or
accumulates down the columns in one call. Accumulations (``cumsum``, ``cumprod``) run down each
column in order, so a path's result never depends on which other paths share its block.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.core.library import PathLibrary

__all__ = ["PathRows", "column_sums", "library_rows"]


class PathRows:
    """The m paths of a library as columns of library-local edge indices (see the module docstring).

    Args:
        indptr: (m + 1,) CSR row pointers of the path-edge incidence.
        indices: (nnz,) edge ids of each path, row by row (the order kept within each column).
        num_edges: E, the number of edges of the graph.

    Attributes:
        edges: (K,) int64 sorted ids of the edges some path uses (library-local index k is ``edges[k]``).
        column: (E,) int64 library-local index of each edge; K for an edge no path uses.
        table: (L, m) int64: ``table[j, i]`` is the local index of path i's j-th edge, K past its end;
            L is the longest path's length.
        by_path: (m, L) int64, the same table path by path (row i: path i's edges), contiguous.
    """

    def __init__(self, indptr: npt.NDArray[np.integer], indices: npt.NDArray[np.integer], num_edges: int) -> None:
        ptr = np.asarray(indptr, dtype=np.int64)
        edge = np.asarray(indices, dtype=np.int64)
        lengths = np.diff(ptr)
        self.num_paths = int(lengths.size)
        self.edges: IntArray = np.unique(edge)
        self.column: IntArray = np.full(num_edges, self.edges.size, dtype=np.int64)
        self.column[self.edges] = np.arange(self.edges.size, dtype=np.int64)
        depth = int(lengths.max(initial=0))
        self.table: IntArray = np.full((depth, self.num_paths), self.edges.size, dtype=np.int64)
        row = np.repeat(np.arange(self.num_paths, dtype=np.int64), lengths)
        position = np.arange(edge.size, dtype=np.int64) - np.repeat(ptr[:-1], lengths)
        self.table[position, row] = self.column[edge]
        self.by_path: IntArray = np.ascontiguousarray(self.table.T)

    @property
    def pad(self) -> int:
        """K, the index of the neutral slot past the library edges."""
        return int(self.edges.size)

    def edge_counts(self, paths: IntArray) -> IntArray:
        """(K,) int64: how many of ``paths`` use each library edge."""
        return np.bincount(self.table[:, paths].ravel(), minlength=self.pad + 1)[:-1]


def column_sums(block: FloatArray) -> FloatArray:
    """(r,) the sum down each column of the (L, r) ``block``, term after term from the first row.

    The last row of ``block.cumsum(axis=0)``, bit for bit, without writing the (L, r) running sums: a
    ``numpy`` sum over the first axis of a C-contiguous array with two or more columns adds row after row
    into the output (only a sum along the contiguous axis adds pairwise, as it would for one column).
    """
    if block.ndim != 2 or block.shape[1] < 2 or not block.flags.c_contiguous:
        return np.asarray(block.cumsum(axis=0)[-1], dtype=np.float64)
    return np.asarray(block.sum(axis=0), dtype=np.float64)


def library_rows(library: PathLibrary) -> PathRows:
    """The :class:`PathRows` of ``library``, built on first use and kept on the library.

    Every episode on a query's library (cached by the planner) starts from the same table.
    """
    built: PathRows | None = library.__dict__.get("_path_rows")
    if built is None:
        csr = library.incidence
        built = PathRows(csr.indptr, csr.indices, library.num_edges)
        object.__setattr__(library, "_path_rows", built)
    return built
