"""A query's training outcomes: the prior's worlds over its graph's edges, plus imputed columns for new edges.

A query joined to off-graph states, or a graph grown by the planner, has edges the training worlds never
checked; each gets a column of imputed outcomes (:func:`~drd_planner.planner.connect.imputed_outcomes`). The
prior's own (n, E) matrix is never copied for that (57 MB on the real-scale helicopter prior): a
:class:`QueryWorlds` is the prior's matrix and its packed columns (:class:`~drd_planner.core.world_columns.
WorldColumns`, built once per prior) with the few new columns beside them. Whoever needs one column, a few,
or the free counts of a subset of worlds asks for just that; :meth:`QueryWorlds.dense` builds the whole
(n, E') matrix only for the rare consumer that needs it (a DiRECt tree of a joined query).
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.world_columns import WorldColumns
from drd_planner.exceptions import ProblemError

__all__ = ["QueryWorlds"]


class QueryWorlds:
    """The (n, E + k) training outcomes of a query: the prior's E columns, then k imputed ones.

    Args:
        base: (n, E) bool, the prior's training worlds (not copied).
        columns: the packed columns of ``base`` (shared by every query of the prior).
        extra: (n, k) bool imputed columns of the query's new edges (edge ids E .. E + k - 1), or None.
    """

    def __init__(self, base: BoolArray, columns: WorldColumns, extra: npt.ArrayLike | None = None) -> None:
        if columns.num_worlds != base.shape[0] or columns.num_edges != base.shape[1]:
            raise ProblemError("the packed columns must be those of the base worlds")
        self.base = base
        self.base_columns = columns
        n = base.shape[0]
        self.extra: BoolArray = (
            np.zeros((n, 0), dtype=bool) if extra is None else np.asarray(extra, dtype=bool).reshape(n, -1)
        )

    @property
    def num_worlds(self) -> int:
        """N."""
        return int(self.base.shape[0])

    @property
    def num_base_edges(self) -> int:
        """E, the prior's edges."""
        return int(self.base.shape[1])

    @property
    def num_edges(self) -> int:
        """E + k."""
        return self.num_base_edges + int(self.extra.shape[1])

    @property
    def shape(self) -> tuple[int, int]:
        """(n, E + k)."""
        return self.num_worlds, self.num_edges

    def column(self, edge: int) -> BoolArray:
        """(n,) the outcomes of one edge (a view for the prior's edges)."""
        e = int(edge)
        if e < self.num_base_edges:
            return self.base[:, e]
        return self.extra[:, e - self.num_base_edges]

    def columns(self, edges: npt.ArrayLike) -> BoolArray:
        """(n, len(edges)) the outcomes of the given edges, in that order."""
        ids = np.asarray(edges, dtype=np.int64).ravel()
        old = ids < self.num_base_edges
        if old.all():
            return np.asarray(self.base[:, ids], dtype=bool)
        out = np.empty((self.num_worlds, ids.size), dtype=bool)
        out[:, old] = self.base[:, ids[old]]
        out[:, ~old] = self.extra[:, ids[~old] - self.num_base_edges]
        return out

    def free_counts(self, rows: BoolArray) -> IntArray:
        """(E + k,) int64: in how many of the (n,) ``rows`` worlds each edge is free."""
        base = self.base_columns.free_counts(rows)
        if self.extra.shape[1] == 0:
            return base
        more = self.extra[np.asarray(rows, dtype=bool)].sum(axis=0, dtype=np.int64)
        return np.concatenate([base, more])

    @cached_property
    def free_fraction(self) -> FloatArray:
        """(E + k,) the fraction of all training worlds in which each edge is free."""
        totals = np.concatenate([self.base_columns.free_totals, self.extra.sum(axis=0, dtype=np.int64)])
        return np.asarray(totals / max(self.num_worlds, 1), dtype=np.float64)

    def with_columns(self, more: npt.ArrayLike) -> QueryWorlds:
        """These outcomes followed by the (n, m) ``more`` columns (edge ids E + k on)."""
        added = np.asarray(more, dtype=bool).reshape(self.num_worlds, -1)
        return QueryWorlds(self.base, self.base_columns, np.concatenate([self.extra, added], axis=1))

    @cached_property
    def dense(self) -> BoolArray:
        """(n, E + k) the whole matrix (the prior's when there are no new columns; a copy otherwise)."""
        if self.extra.shape[1] == 0:
            return self.base
        return np.concatenate([self.base, self.extra], axis=1)
