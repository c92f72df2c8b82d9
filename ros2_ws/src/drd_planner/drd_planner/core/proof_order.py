"""The expected cost of proving each path, kept current through an episode: the ``"per_check"`` region rule.

The rule (:mod:`~drd_planner.core.region_rule`) ranks alive paths by log p_i - log E_i, where E_i is the
expected cost of resolving path i by checking its unchecked edges cheapest-first: in the order
c_e / (1 - theta_e) ascending (ties to the lower edge id),

    E_i = sum_k c_(k) * prod_{j<k} theta_(j).

Computing E_i for every path at every selection means sorting every path again whenever the bias changes,
which the posterior leaf does after nearly every outcome. :class:`ProofOrder` instead keeps, per path, its
order, its E_i and whether either is out of date: an outcome makes E_i out of date only for the paths
through the checked edge, a new bias for every path; nothing is recomputed until a path is asked for. And
:meth:`ProofOrder.best_path` asks for very few: a path's score is at most log p_i - log L_i, with

    L_i = c * sum_{k < n_i} q_i^k  <=  E_i

(c the cheapest edge cost, q_i the smallest theta among the n_i unchecked edges of path i: every term of
E_i is at least the matching term of L_i), and a path whose bound is below the best exact score so far can
neither win nor tie. The bound needs no sorting; on the shipped helicopter prior it leaves about 4 of 500
paths to score exactly. Among fewer or shorter paths the bounds cost more calls than they save, and every
path is scored.

E_i is computed along the path's order: the running product of theta over the edges before each one (a
checked edge counts 1), times its cost (0 once checked), summed, as ``numpy`` accumulations down each
path's column (:mod:`~drd_planner.core.path_rows`), or, for a few paths, the same products and sums one
after the other in Python floats (the same numbers: IEEE products and sums in the same order). So a path's
E_i never depends on which other paths are computed with it, and any sequence of updates reaches, bit for
bit, the numbers a new :class:`ProofOrder` computes for the same bias and checked edges.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.path_rows import PathRows, column_sums

__all__ = ["ProofOrder"]

#: L_i is shrunk by this relative margin, far above the rounding of E_i and of the closed form of L_i.
_BOUND_MARGIN = 1e-9
#: :meth:`ProofOrder.best_path` first scores this many of the most probable paths (and the last choice).
_FIRST_SCORED = 4
#: Up to this many table slots (alive paths x the table's depth) :meth:`ProofOrder.best_path` scores every
#: path: cheaper than the bounds' extra calls (a call of :meth:`ProofOrder._costs_of` costs about 20 us and
#: 0.03 us a slot; the bounds about 60 us more).
_SCORE_ALL_SLOTS = 1024
#: Up to this many table slots (paths out of date x the table's depth), E_i is recomputed with Python floats:
#: ``numpy``'s cost per call dominates there (about 20 us a call of :meth:`ProofOrder._costs_of`, 0.4 us a slot).
_SCALAR_SLOTS = 48


class ProofOrder:
    """Every path's cheapest proof order and expected proof cost E_i (see the module docstring).

    Updates (cheap, nothing is recomputed until asked): :meth:`mark_checked` after an outcome,
    :meth:`set_theta` after a new bias. Queries: :meth:`costs` (E_i of given paths) and
    :meth:`best_path` (the ``"per_check"`` choice).

    Args:
        rows: the library as a table of library-local edge indices.
        theta: (E,) probability that each edge is free, in (0, 1].
        edge_costs: (E,) positive check costs.
        checked: (E,) edges already checked (they cost nothing more), or None.
    """

    def __init__(
        self,
        rows: PathRows,
        theta: FloatArray,
        edge_costs: FloatArray,
        *,
        checked: BoolArray | None = None,
    ) -> None:
        self._rows = rows
        self.num_paths = rows.num_paths
        lib, pad = rows.edges, rows.pad
        self._edge_cost = np.asarray(np.asarray(edge_costs, dtype=np.float64)[lib], dtype=np.float64)
        cheapest = float(self._edge_cost.min())  # L_i's c
        self._scale = cheapest * (1.0 - _BOUND_MARGIN)
        self._log_cheapest = float(np.log(cheapest))
        # Per library edge, plus the pad slot K: whether it is unchecked, its bias and order key, and the
        # two factors of E_i: theta and the cost while unchecked, 1 and 0 once checked (and in the pad).
        self._unchecked = np.ones(pad + 1, dtype=bool)
        self._unchecked[pad] = False
        if checked is not None:
            self._unchecked[:pad] &= ~np.asarray(checked, dtype=bool)[lib]
        self._theta = np.ones(pad + 1)
        self._theta[:pad] = np.asarray(theta, dtype=np.float64)[lib]
        self._key = np.full(pad + 1, np.inf)
        self._key[:pad] = self._edge_cost / np.maximum(1.0 - self._theta[:pad], 1e-300)
        self._factor = np.where(self._unchecked, self._theta, 1.0)
        self._cost = np.where(self._unchecked, np.append(self._edge_cost, 0.0), 0.0)
        self._left = self._unchecked[rows.table].sum(axis=0)  # n_i, unchecked edges per path
        self._order = rows.table.copy()  # a path's column is sorted when the path is next asked for
        self._values = np.zeros(self.num_paths, dtype=np.float64)  # E_i
        self._stale = np.ones(self.num_paths, dtype=bool)  # E_i to recompute
        self._unsorted = np.ones(self.num_paths, dtype=bool)  # order to sort again
        self._last = -1  # the last choice of best_path

    def mark_checked(self, edge: int, paths: npt.NDArray[np.integer]) -> None:
        """``edge`` was checked: it costs nothing more; ``paths`` (those through it) get a new E_i."""
        k = int(self._rows.column[edge])
        if not self._unchecked[k]:  # checked before, or not a library edge (the pad)
            return
        self._unchecked[k] = False
        self._factor[k] = 1.0
        self._cost[k] = 0.0
        self._left[paths] -= 1
        self._stale[paths] = True

    def set_theta(self, theta: FloatArray) -> None:
        """A new (E,) bias: new keys; every path's order and E_i are recomputed when it is next asked for."""
        self.set_library_theta(np.asarray(theta, dtype=np.float64)[self._rows.edges])

    def set_library_theta(self, theta: FloatArray, *, changed: bool = False) -> None:
        """:meth:`set_theta` with the (K,) bias of the library edges (``rows.edges``) only.

        ``changed``: the caller knows some value differs from the current bias (no comparison).
        """
        pad = self._rows.pad
        if not changed and not (theta != self._theta[:pad]).any():
            return
        self._theta[:pad] = theta
        self._key[:pad] = self._edge_cost / np.maximum(1.0 - theta, 1e-300)
        np.copyto(self._factor[:pad], theta, where=self._unchecked[:pad])
        self._stale.fill(True)
        self._unsorted.fill(True)

    def costs(self, rows: BoolArray) -> FloatArray:
        """(m,) E_i of each path in ``rows`` (m,); 0 elsewhere and for a path with nothing left to check."""
        asked = np.flatnonzero(rows)
        out = np.zeros(self.num_paths, dtype=np.float64)
        out[asked] = self._costs_of(asked)
        return out

    def best_path(self, log_p: FloatArray, paths: IntArray) -> int:
        """The ``"per_check"`` choice among ``paths``: argmax of log p_i - log E_i, the first path on ties.

        The same path as the argmax of :func:`~drd_planner.core.region_rule.region_scores` over
        :meth:`costs` (a path with nothing left to check scores +inf). Up to :data:`_SCORE_ALL_SLOTS` slots every
        path is scored; among more, E_i is computed only for the paths the bounds of the module docstring
        leave in: the last choice and the most probable paths
        are scored first; their best score is the bar. A path can reach the bar only if log p_i - log c
        does (cheap, every path), and then only if log p_i - log L_i does; the best of those is scored.

        Args:
            log_p: (r,) log p_i of ``paths`` (finite: alive paths).
            paths: (r,) ascending path ids, r >= 1.
        """
        if paths.size * self._rows.table.shape[0] > _SCORE_ALL_SLOTS:
            first = log_p.argpartition(paths.size - _FIRST_SCORED)[-_FIRST_SCORED:]
            last = int(np.searchsorted(paths, self._last))
            if last < paths.size and paths[last] == self._last:
                first = np.append(first, last)
            bar = float(self._scores(log_p[first], paths[first]).max())
            if bar == np.inf:  # a path with nothing left to check: the first such path wins
                left = np.flatnonzero(self._left[paths] == 0)[:1]
            else:  # every path scoring >= bar passes both bounds (the first ones' E_i are cached)
                left = np.flatnonzero(log_p - self._log_cheapest >= bar)
                left = left[log_p[left] - self._log_lower_bounds(paths[left]) >= bar]
            log_p, paths = log_p[left], paths[left]
        self._last = int(paths[int(self._scores(log_p, paths).argmax())])
        return self._last

    def _scores(self, log_p: FloatArray, paths: IntArray) -> FloatArray:
        """(r,) log p_i - log E_i of ``paths`` (+inf where E_i = 0: nothing left to check)."""
        costs = self._costs_of(paths)
        log_e = np.full(paths.size, -np.inf)
        np.log(costs, out=log_e, where=costs > 0.0)
        return np.asarray(log_p - log_e, dtype=np.float64)

    def _log_lower_bounds(self, paths: IntArray) -> FloatArray:
        """(r,) log L_i of ``paths``, L_i shrunk by :data:`_BOUND_MARGIN` (-inf: nothing left to check)."""
        # q: the smallest factor of each path (checked edges and the pad count 1); n: its unchecked edges.
        q = self._factor[self._rows.by_path[paths]].min(axis=1)
        n = self._left[paths]
        full = q >= 1.0  # every factor 1: L_i = n_i c (0 when nothing is left to check)
        ratio = np.where(full, 0.5, q)  # sum_{k<n} q^k = (1 - q^n) / (1 - q), without cancelling
        geometric = -np.expm1(n * np.log1p(ratio - 1.0)) / (1.0 - ratio)
        geometric[full] = n[full]
        out = np.full(paths.size, -np.inf)
        np.log(geometric * self._scale, out=out, where=geometric > 0.0)
        return out

    def _costs_of(self, paths: IntArray) -> FloatArray:
        """(r,) E_i of ``paths``, recomputed for those out of date (and sorted again after a new bias)."""
        todo = paths[self._stale[paths]]
        if todo.size * self._rows.table.shape[0] > _SCALAR_SLOTS:
            block = self._order[:, todo]
            if self._unsorted[todo].any():  # a path out of order is out of date too
                by = np.lexsort((block, self._key[block]), axis=0)  # (key, local index): ties by edge id
                block = block[by, np.arange(todo.size)]
                self._order[:, todo] = block
                self._unsorted[todo] = False
            # Term j of E_i: its cost times the product of theta over the edges before it (1 for j = 0).
            products = np.multiply.accumulate(self._factor[block], axis=0)
            terms = self._cost[block]
            terms[1:] *= products[:-1]
            self._values[todo] = column_sums(terms)
            self._stale[todo] = False
        elif todo.size:
            self._values[todo] = self._scalar_costs(todo)
            self._stale[todo] = False
        return self._values[paths]

    def _scalar_costs(self, todo: IntArray) -> list[float]:
        """E_i of the (r,) ``todo`` paths, each sorted and summed term by term in Python floats.

        The same operations in the same order as the columns of :meth:`_costs_of` (a product, then a
        running sum, both from the first edge on; the pad slots add 0), so the same numbers bit for bit.
        The order is made from the current keys and not kept (``_order`` keeps what the columns sorted).
        """
        block = self._rows.by_path[todo]  # (r, L): each path's slots, padded with K
        rows = zip(
            self._key[block].tolist(),
            block.tolist(),
            self._factor[block].tolist(),
            self._cost[block].tolist(),
            strict=True,
        )
        out = []
        for row in rows:
            # (key, local index) order; the pad slots (key inf, index K, factor 1, cost 0) come last.
            ordered = sorted(zip(*row, strict=True))
            total = ordered[0][3]
            product = ordered[0][2]
            for _, _, factor, cost in ordered[1:]:
                total += cost * product
                product *= factor
            out.append(total)
        return out
