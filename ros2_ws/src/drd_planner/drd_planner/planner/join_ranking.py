"""Which joins an off-graph state gets next: the connector's ranking reordered by the prior, imputed on demand.

When an off-graph start's or goal's first joins do not suffice (:mod:`~drd_planner.planner.join_growth`), it is
offered more, best first by the lazy search's own weight of each joining motion under the prior:
``-log theta + lambda * length / mean edge length`` (the graph fallback's weight; theta the weighted share of
training worlds in which the motion's imputed outcome is free, at least 1e-3). Imputing a motion (its sketched
points matched to the nearest graph edges, then counted over the packed training worlds) is the costly part: on
``heli_lines`` every join of a state (3 900 motions) took about 100 ms, more than the round it served, which
offers 64.

:class:`PriorRanking` imputes in the connector's order (shortest first), as far as the round asks. A motion's
weight is at least its length term, so once the motions imputed so far include one whose weight is at most the
least length term of every motion not yet imputed, the motions up to it are final: the same order, ties kept in
the connector's order, as a stable sort of every motion's weight. On ``heli_lines`` starts 150 m off the lattice
whose growth found a path in its first rounds planned in 130-185 ms instead of 200-230, with the same checks; a
state whose likely-free joins are all far still imputes them all, in a few steps (256, 512, ... motions).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.core.world_columns import WorldColumns
from drd_planner.exceptions import ProblemError
from drd_planner.planner.connect import EdgeSampleIndex, imputed_columns, imputed_shares
from drd_planner.planner.graph_fallback import LENGTH_WEIGHT
from drd_planner.planner.prior import WorldPrior

__all__ = ["FIRST_IMPUTED", "PriorRanking", "length_terms", "prior_surprise"]

#: Motions imputed in the first step of a :class:`PriorRanking` at least (count); each later step doubles.
FIRST_IMPUTED = 256


def length_terms(lengths: FloatArray, prior: WorldPrior) -> FloatArray:
    """(M,) ``lambda * length / mean edge length`` of motions of ``lengths`` (M,) (the graph's unit)."""
    mean = float(np.mean(prior.graph.lengths)) if prior.graph.num_edges else 1.0
    return np.asarray(LENGTH_WEIGHT * lengths / (mean if mean > 0 else 1.0), dtype=np.float64)


def prior_surprise(
    points: FloatArray, index: EdgeSampleIndex, prior: WorldPrior, columns: WorldColumns | None = None
) -> FloatArray:
    """(M,) ``-log theta`` of M sketched motions, theta the weighted share of training worlds imputing each free.

    Args:
        points: (M, P, D') positions along each motion.
        index: points along the prior's graph edges.
        prior: its training worlds (required) and their weights.
        columns: the same worlds as packed columns (read faster than the worlds' rows), when at hand.
    """
    if prior.worlds is None:
        raise ProblemError("the prior's surprise of a motion needs training worlds")
    if columns is None:
        theta = np.average(imputed_columns(index, prior.worlds, list(points)), axis=0, weights=prior.world_weights)
    else:  # the same numbers, counted on the packed columns
        theta = imputed_shares(index, columns, points, prior.world_weights)
    return np.asarray(-np.log(np.clip(theta, 1e-3, 1.0)), dtype=np.float64)


class PriorRanking:
    """Vertices by their joining motion's weight (ties: the connector's order), imputed only as far as asked.

    See the module docstring; :meth:`first` gives the order's head.

    Args:
        ranking: (M,) vertex ids in the connector's order.
        floor: (M,) a lower bound of each motion's weight (its length term, :func:`length_terms`).
        surprise: the rest of the weight of the motions at the given (k,) positions of ``ranking``, >= 0 (k,).
    """

    def __init__(self, ranking: IntArray, floor: FloatArray, surprise: Callable[[IntArray], FloatArray]) -> None:
        if floor.shape != ranking.shape:
            raise ProblemError(f"a weight floor per ranked vertex expected: {floor.shape} for {ranking.shape}")
        self._ranking = np.asarray(ranking, dtype=np.int64)
        self._floor = np.asarray(floor, dtype=np.float64)
        self._surprise = surprise
        # The least floor from each position on (inf past the end): no motion not yet imputed weighs less.
        self._rest_floor = np.append(np.minimum.accumulate(self._floor[::-1])[::-1], np.inf)
        self._weights = np.zeros(0)
        self._final = np.zeros(0, dtype=np.int64)

    @classmethod
    def of_prior(
        cls,
        ranking: IntArray,
        lengths: FloatArray,
        points: FloatArray,
        index: EdgeSampleIndex,
        prior: WorldPrior,
        columns: WorldColumns | None = None,
    ) -> PriorRanking:
        """The ranking of motions of ``lengths`` (M,) sketched at ``points`` (M, P, D') under ``prior``.

        A prior without training worlds keeps the connector's order (:meth:`as_given`); ``columns``: its worlds
        packed (read faster than the worlds' rows), when at hand.
        """
        if prior.worlds is None:  # the connector's order: nothing to impute
            return cls.as_given(ranking)
        return cls(ranking, length_terms(lengths, prior), lambda at: prior_surprise(points[at], index, prior, columns))

    @classmethod
    def as_given(cls, ranking: IntArray) -> PriorRanking:
        """The connector's own order (every weight 0: nothing to impute)."""
        return cls(ranking, np.zeros(ranking.size), lambda at: np.zeros(at.size))

    @property
    def size(self) -> int:
        """M, the vertices ranked."""
        return int(self._ranking.size)

    @property
    def imputed(self) -> int:
        """How many motions have been imputed so far (the connector's first ones)."""
        return int(self._weights.size)

    def first(self, count: int) -> IntArray:
        """(k,) the first ``k >= min(count, M)`` vertices of the order (every one known final), imputing as needed."""
        while self._final.size < min(count, self.size):
            step = max(FIRST_IMPUTED, self.imputed, count - self._final.size)
            at = np.arange(self.imputed, min(self.imputed + step, self.size))
            self._weights = np.concatenate([self._weights, self._surprise(at) + self._floor[at]])
            order = np.argsort(self._weights, kind="stable")  # ties: the connector's order
            known = np.count_nonzero(self._weights <= self._rest_floor[self.imputed])
            self._final = self._ranking[order[:known]]  # weights at most any motion's not imputed
        return self._final
