"""The probe: on a new query, check first the one path the training worlds say is more likely free than not.

A new query's library is each search world's shortest free path; building it costs milliseconds (a search per
world the union does not settle, the library's incidence, BiSECt's set-up) while a robot's short query is often
verified by checking the few edges of one path. The **union path** is the shortest path over the edges free in
*any* search world: in every search world where all its edges are free it is that world's shortest free path (no
shorter path exists over edges free somewhere), and its probability of being free is the (weighted) fraction of
training worlds in which all its edges are free. When that probability is at least ``probability`` (default
one half: the path is more likely free than blocked), the planner checks this path's edges before building the
library, the edge least often free in the training worlds first (ties in path order), so that a blocked path
is found out early. If every edge is free, that verified path is the answer, as short as any the library could
give. Once one is blocked the probe stops, the library is built, and BiSECt goes on knowing every outcome.

The threshold was chosen on held-out worlds and queries other than the reported benchmark's (four shipped
priors, 40 random vertex queries each): there the union path was free in 27 of 29 (heli_wires) and in every one
(heli_terrain 39, the arm 33, heli_lines 39) of the queries whose probability was at least one half.

The probe is used by the method's policy (``direct_bisect``) on queries without a precomputed tree, between
vertices or with a start or goal off the graph (its motions' outcomes imputed in the training worlds), whether
the online stage is BiSECt from the root (switch threshold 1) or a DiRECt tree grown online (below 1): after a
blocked edge that tree is walked on the probe's outcomes (a test whose outcome is known is followed, not asked
again) and BiSECt gets them all at the switch. On held-out random queries of the three authors' sets where
validation grows deep trees (60 queries, seed 3, eta 0.01) the mean checks went from 17.88 to 17.48 (Baffle),
16.50 to 16.30 (SE(2) Baffle) and stayed at 85.90 (Maze). A stored query's tree and the baselines are unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.core.episode import EdgeOracle, EpisodeResult, run_episode
from drd_planner.exceptions import ProblemError
from drd_planner.planner.goal_trees import SearchWorlds
from drd_planner.planner.query_graph import QueryGraph
from drd_planner.planner.query_library import union_path

__all__ = [
    "DEFAULT_PROBE_PROBABILITY",
    "PROBE_POLICIES",
    "Probe",
    "ProbePolicy",
    "check_probe_probability",
    "probe_episode",
    "union_probe",
]

#: The least probability of being free (over the training worlds) at which the union path is checked first.
DEFAULT_PROBE_PROBABILITY = 0.5
#: The library-stage policies a probe precedes (the method; the baselines stay as they are).
PROBE_POLICIES = frozenset({"direct_bisect"})


@dataclass(frozen=True)
class Probe:
    """The union path of a query and what the training worlds say about it.

    Attributes:
        edges: (L,) int64 edge ids of the path, start to goal.
        free_probability: the weighted fraction of training worlds in which every edge of it is free.
        order: (L,) the same edges in the order they are checked: least often free first (ties in path order).
    """

    edges: IntArray
    free_probability: float
    order: IntArray


def check_probe_probability(probability: float | None) -> float | None:
    """``probability`` as it is when None or in [0, 1] (ProblemError otherwise)."""
    if probability is not None and not 0.0 <= probability <= 1.0:
        raise ProblemError(f"probe_probability must lie in [0, 1] or be None, got {probability}")
    return probability


def union_probe(
    search: SearchWorlds, query: QueryGraph, weights: FloatArray | None, *, probability: float
) -> Probe | None:
    """The query's probe, or None when its union path is less likely free than ``probability`` (or absent).

    Args:
        search: the prior's search worlds (a graph goal's union tree is kept per goal).
        query: the query's graph and training outcomes (an off-graph state's motions imputed).
        weights: (n,) the training worlds' prior weights, or None for uniform.
        probability: the least probability of being free, in [0, 1].
    """
    check_probe_probability(probability)
    if query.worlds is None:
        return None
    start = query.start if query.start_joins is None else query.start_joins
    goal = query.goal if query.goal_joins is None else query.goal_joins
    edges = union_path(search, start, goal)
    if edges.size == 0:
        return None
    columns = query.worlds.columns(edges)  # (n, L)
    free = float(np.average(columns.all(axis=1), weights=weights))
    if free < probability:
        return None
    share = np.average(columns, axis=0, weights=weights)  # (L,) how often each edge is free
    order = edges[np.argsort(share, kind="stable")]
    return Probe(edges, free, np.asarray(order, dtype=np.int64))


class ProbePolicy:
    """Checks a probe's edges in its order, and nothing once one is blocked.

    A :class:`~drd_planner.core.episode.GraphPathPolicy` (name and stage ``probe``): its path is the probe's, so
    the runner ends its episode with FOUND once every edge was checked free and NO_PATH once one is blocked.
    """

    def __init__(self, probe: Probe) -> None:
        self._path = probe.edges
        self._order = probe.order.tolist()
        self._next = 0
        self._blocked = False

    @property
    def name(self) -> str:
        """``probe``."""
        return "probe"

    @property
    def stage(self) -> str:
        """``probe``."""
        return "probe"

    @property
    def stops_on_library_path(self) -> bool:
        """False: the probe's episode has no library."""
        return False

    @property
    def max_checks(self) -> int | None:
        """None: the plan's budget only."""
        return None

    def proposed_path(self) -> IntArray | None:
        """The probe's path until one of its edges is blocked, then None."""
        return None if self._blocked else self._path

    def select(self) -> int | None:
        """The next edge of the path in the probe's order; None after a blocked one or the last."""
        if self._blocked or self._next >= len(self._order):
            return None
        return int(self._order[self._next])

    def observe(self, edge: int, free: bool) -> None:
        """Step on; a blocked edge ends the probe."""
        if self._next < len(self._order) and edge == self._order[self._next]:
            self._next += 1
        self._blocked |= not free


def probe_episode(
    probe: Probe,
    edge_costs: FloatArray,
    oracle: EdgeOracle,
    *,
    max_checks: int | None,
    deadline: float | None,
) -> EpisodeResult:
    """Check the probe's path: FOUND when every edge is free, NO_PATH at the first blocked one, or a budget's end.

    Args:
        probe: the query's probe.
        edge_costs: (E,) the query graph's check costs.
        oracle: the plan's oracle.
        max_checks: the plan's check budget (None: none).
        deadline: the plan's deadline on ``time.perf_counter()`` (None: none).
    """
    return run_episode(None, edge_costs, ProbePolicy(probe), oracle, max_checks=max_checks, deadline=deadline)
