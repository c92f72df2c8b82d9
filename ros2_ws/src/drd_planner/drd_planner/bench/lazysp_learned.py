"""LazySP selectors that learn from the training worlds (Bhardwaj, Choudhury, Boots, Srinivasa, RSS 2019).

"Leveraging Experience in Lazy Search" compares its learned selector with selectors built from the
training data. Two of them are reimplemented here from the paper's description, on the LazySP loop of
:class:`drd_planner.core.lazysp.LazySP` (shortest path with known-blocked edges deleted; check one
unchecked edge of it; stop once it is checked free):

``lazysp_posterior`` ("PostFast")
    check the unchecked path edge most likely to be blocked given every outcome so far.
``lazysp_posterior_delta`` (posterior x Delta-length)
    check the unchecked path edge maximising P(blocked | outcomes) x Delta_len(e), where
    Delta_len(e) is how much longer the lazy shortest path gets when e is deleted as well: an edge
    that is likely blocked *and* whose loss rules out the short detours is worth more.

The posterior is :class:`drd_planner.core.posterior.ConsistentWorldsBias` over every graph edge (not
only the library's): the training worlds that agree with every checked edge, shrunk toward the
training marginal by a pseudo-count kappa (in worlds) so that it never collapses to 0/1 once few
worlds remain, and falls back to the marginal when none does::

    P(e blocked | outcomes) = 1 - (sum_{h in C} w_h X[h, e] + kappa * mean_e) / (sum_{h in C} w_h + kappa)

(no alpha blend toward 1/2 here: alpha is 1). The registry always passes kappa =
``DEFAULT_PSEUDO_COUNT`` (20 worlds); a run's ``--kappa`` tunes ``direct_bisect``'s leaf, not these.

Ranking rules (deterministic, no randomness): ``posterior`` takes the highest posterior, ties to the
earlier edge on the path. ``posterior_delta`` first takes the *bridges*, edges whose deletion
disconnects start and goal in the lazy graph (Delta_len infinite): each lies on every remaining path,
so it must be checked anyway and, if blocked, ends the search at once; among bridges the highest
posterior wins. Otherwise the highest score wins, scores within a relative 1e-9 count as equal, and
ties go to the higher posterior, then the earlier edge. Delta_len is one batched Dijkstra over copies
of the graph (:meth:`drd_planner.core.lazysp.GraphArcs.deletion_lengths`), recomputed only after a
blocked outcome (a free outcome changes neither the lazy graph nor its path).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Final

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.lazysp import DEFAULT_MAX_CHECKS, LazySP, LazySPSettings
from drd_planner.core.posterior import ConsistentWorldsBias, TrainingOutcomes
from drd_planner.exceptions import ProblemError

#: The learned selectors, in the order of :data:`LEARNED_LAZYSP_POLICIES`.
LEARNED_SELECTORS: Final = ("posterior", "posterior_delta")
#: Their registry names.
LEARNED_LAZYSP_POLICIES: Final = tuple(f"lazysp_{s}" for s in LEARNED_SELECTORS)
#: Scores within this relative distance of the best count as tied (Dijkstra sums in other orders).
SCORE_RTOL: Final = 1e-9


def all_edge_outcomes(train_free: npt.ArrayLike, weights: npt.ArrayLike | None = None) -> TrainingOutcomes:
    """The training worlds over every graph edge, for :class:`PosteriorLazySP`.

    Args:
        train_free: (n_train, E) bool, True where edge e is free in training world h.
        weights: (n_train,) non-negative prior weights, or None for uniform.
    """
    x = np.asarray(train_free, dtype=bool)
    if x.ndim != 2:
        raise ProblemError(f"training worlds must be (n_train, E) bool; got shape {x.shape}")
    return TrainingOutcomes(x, np.arange(x.shape[1], dtype=np.int64), x.shape[1], weights=weights)


@dataclass(frozen=True)
class PosteriorSettings:
    """How :class:`PosteriorLazySP` ranks edges and when it gives up.

    Attributes:
        pseudo_count: kappa > 0, in worlds (the registry's default is ``DEFAULT_PSEUDO_COUNT``, 20).
        delta: rank by posterior x Delta_len (``lazysp_posterior_delta``) instead of the posterior.
        max_checks: check budget the runner enforces (None: unlimited).
    """

    pseudo_count: float
    delta: bool = False
    max_checks: int | None = DEFAULT_MAX_CHECKS


class PosteriorLazySP(LazySP):
    """LazySP whose selector ranks path edges by the posterior of being blocked (optionally x Delta_len).

    Args:
        graph: the explicit graph (LazySP searches it with the graph's lengths).
        start: start vertex.
        goal: goal vertex.
        outcomes: the training worlds over all E edges (:func:`all_edge_outcomes`).
        settings: kappa, the Delta_len option and the check budget.
        name: registry name (default ``lazysp_posterior`` or ``lazysp_posterior_delta``).
        observations: outcomes already known (edge -> free).
    """

    def __init__(
        self,
        graph: ExplicitGraph,
        start: int,
        goal: int,
        outcomes: TrainingOutcomes,
        settings: PosteriorSettings,
        *,
        name: str | None = None,
        observations: Mapping[int, bool] | None = None,
    ) -> None:
        if outcomes.num_edges != graph.num_edges or outcomes.library_edges.size != graph.num_edges:
            raise ProblemError(
                f"the training worlds cover {outcomes.library_edges.size} of {outcomes.num_edges} edges, "
                f"but the posterior LazySP needs all {graph.num_edges} graph edges (all_edge_outcomes)"
            )
        # Set before LazySP's constructor, which replays ``observations`` through observe().
        self._posterior = ConsistentWorldsBias(outcomes, pseudo_count=settings.pseudo_count, alpha=1.0)
        self._delta = settings.delta
        self._delta_cache: dict[int, float] = {}
        selector = LEARNED_SELECTORS[1] if settings.delta else LEARNED_SELECTORS[0]
        super().__init__(
            graph,
            start,
            goal,
            LazySPSettings(max_checks=settings.max_checks),
            name=name or f"lazysp_{selector}",
            observations=observations,
        )

    @property
    def num_consistent(self) -> int:
        """How many training worlds agree with every outcome so far."""
        return self._posterior.num_consistent

    def observe(self, edge: int, free: bool) -> None:
        """Drop the training worlds that disagree, then LazySP's update (a blocked edge is deleted)."""
        self._posterior.observe(edge, free)
        if not free:
            self._delta_cache.clear()
        super().observe(edge, free)

    def blocked_probability(self) -> FloatArray:
        """(E,) P(edge blocked | outcomes so far), kappa-shrunk toward the training marginal."""
        return 1.0 - self._posterior.theta()

    def delta_lengths(self, edges: IntArray) -> FloatArray:
        """(m,) growth of the lazy shortest path's length when each edge is deleted too (inf: bridge).

        In length units; cached until the next blocked outcome.
        """
        todo = np.asarray([e for e in edges.tolist() if e not in self._delta_cache], dtype=np.int64)
        if todo.size:
            base, lengths = self._arcs.deletion_lengths(self._start, self._goal, self._weights, todo)
            growth = np.where(np.isfinite(lengths), np.maximum(lengths - base, 0.0), np.inf)
            self._delta_cache.update(zip(todo.tolist(), growth.tolist(), strict=True))
        return np.asarray([self._delta_cache[e] for e in edges.tolist()], dtype=np.float64)

    def _position(self, path: IntArray, checked: BoolArray) -> int:
        open_pos = np.flatnonzero(~checked)
        candidates = path[open_pos]
        blocked = self.blocked_probability()[candidates]
        if not self._delta:
            return int(open_pos[int(np.argmax(blocked))])  # argmax: the first maximum
        return int(open_pos[delta_choice(blocked, self.delta_lengths(candidates))])


def delta_choice(blocked: FloatArray, delta: FloatArray) -> int:
    """Index of the candidate ``lazysp_posterior_delta`` checks (rules in the module docstring).

    Args:
        blocked: (m,) posterior of being blocked, in path order.
        delta: (m,) Delta_len, inf for bridges.
    """
    bridge = np.isinf(delta)
    if bridge.any():
        rows = np.flatnonzero(bridge)
        return int(rows[int(np.argmax(blocked[rows]))])
    score = blocked * delta
    best = float(score.max())
    tied = np.flatnonzero(score >= best - SCORE_RTOL * abs(best))
    return int(tied[int(np.argmax(blocked[tied]))])
