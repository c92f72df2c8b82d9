"""The complete last stage: lazy search over the whole graph once the library has no free path left.

A path library is a small subset of the graph's paths; in a world unlike the training worlds every one
of them can be blocked while the graph still has a free path. The planner then goes on with LazySP over
the whole graph, starting from every outcome already checked in the plan. Its selector checks from the
end of the lazy path whose known-free region (vertices reached over checked-free edges) is smaller
(``balanced`` in :mod:`drd_planner.core.lazysp`): when start or goal is walled in, the checks go to that
wall. Measured on the random queries of the 2D Forest and MovingWall sets (60 each), the checks per
episode in worlds without a free path: forward 363 / 206, alternate 78 / 55, fail-fast (least likely free
edge first) 92 / 74; in worlds with one all three need about the same. On all 100 queries, balanced against
alternate in worlds without a free path: Maze 209 / 266, Forest 38 / 53, MovingWall 28 / 46, SE(2) Baffle
51 / 57, OneWall 34 / 50; with a free path within 0.6 checks of each other.
Its lazy edge weights come from the prior:

    w_e = -log theta_e + lambda * length_e / mean length,

where theta_e is the probability that e is free given the checks so far: the training worlds that
agree with every outcome, shrunk toward the training marginal with kappa pseudo-worlds (as the
posterior leaf, :mod:`drd_planner.core.posterior`), mixed with 1/2 by 1 - alpha. A checked-free edge
has theta = 1 and weighs only its length term; a checked-blocked edge is deleted. The lazy shortest
path is so the most probable free path, and among nearly equally probable ones the shortest
(lambda = :data:`LENGTH_WEIGHT`); with plain lengths as weights the same sets needed 28 and 19 checks
in worlds with a free path instead of 14 and 10. LazySP stops only when its path is checked free or start and goal are
disconnected by the blocked edges, so "no path" is an exact statement about the graph.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from drd_planner.arrays import BoolArray, FloatArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.planner.query_worlds import QueryWorlds

#: LazySP selector of the graph stage (see the module doc for the measurement behind it).
FALLBACK_SELECTOR = "balanced"
#: lambda: the weight of the (normalised) edge length against -log theta.
LENGTH_WEIGHT = 0.1
#: kappa of the fallback's posterior when the prior gives none, in worlds.
DEFAULT_FALLBACK_KAPPA = 20.0


def posterior_free_probability(
    worlds: QueryWorlds | BoolArray | None,
    weights: FloatArray | None,
    outcomes: Mapping[int, bool],
    *,
    num_edges: int,
    alpha: float,
    pseudo_count: float,
) -> FloatArray:
    """(E,) P(edge free | outcomes): consistent training worlds, shrunk to the marginal, clamped on checks.

    Args:
        worlds: (n, E) training outcomes (a query's, or a matrix), or None (then 1/2 on every unchecked edge).
        weights: (n,) prior weights, or None for uniform.
        outcomes: checked edges and their outcome.
        num_edges: E.
        alpha: weight of the data term.
        pseudo_count: kappa > 0.
    """
    theta = np.full(num_edges, 0.5)
    if isinstance(worlds, QueryWorlds):
        if weights is None:  # counts from the packed columns: a popcount per word, no pass over (n, E)
            consistent = np.ones(worlds.num_worlds, dtype=bool)
            for edge, free in outcomes.items():
                consistent &= worlds.column(edge) == free
            counts = worlds.free_counts(consistent)
            data = (counts + pseudo_count * worlds.free_fraction) / (float(consistent.sum()) + pseudo_count)
            theta = alpha * data + (1.0 - alpha) * 0.5
            for edge, free in outcomes.items():
                theta[edge] = 1.0 if free else 0.0
            return np.asarray(theta, dtype=np.float64)
        worlds = worlds.dense
    if worlds is not None:
        consistent = np.ones(worlds.shape[0], dtype=bool)
        for edge, free in outcomes.items():
            consistent &= worlds[:, edge] == free
        if weights is None:  # counts: no (n, E) float copy of the worlds
            mass, free_mass = float(consistent.sum()), worlds[consistent].sum(axis=0, dtype=np.float64)
            marginal = worlds.mean(axis=0, dtype=np.float64)
        else:
            w = weights / weights.mean()
            mass, free_mass = float(w[consistent].sum()), w[consistent] @ worlds[consistent]
            marginal = (w @ worlds) / w.sum()
        data = (free_mass + pseudo_count * marginal) / (mass + pseudo_count)
        theta = alpha * data + (1.0 - alpha) * 0.5
    for edge, free in outcomes.items():
        theta[edge] = 1.0 if free else 0.0
    return np.asarray(theta, dtype=np.float64)


def fallback_edge_weights(graph: ExplicitGraph, theta: FloatArray) -> FloatArray:
    """(E,) finite lazy weights -log theta + lambda * length / mean length.

    Blocked edges (theta 0) get only their length term here: the search deletes them by their outcome.
    """
    lengths = np.asarray(graph.lengths, dtype=np.float64)
    mean = float(lengths.mean()) if lengths.size and lengths.mean() > 0 else 1.0
    with np.errstate(divide="ignore"):
        surprise = -np.log(np.clip(theta, 0.0, 1.0))
    surprise[~np.isfinite(surprise)] = 0.0
    return np.asarray(surprise + LENGTH_WEIGHT * lengths / mean, dtype=np.float64)
