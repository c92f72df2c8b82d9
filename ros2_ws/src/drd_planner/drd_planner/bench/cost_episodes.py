"""One policy on one query at one check cost: the time to a verified plan of ``drd bench --check-cost-ms``.

Queries come in three kinds (:data:`QUERY_KINDS`): ``stored`` (the prior's precomputed query), ``new``
(random vertex pairs) and ``off_graph`` (start and goal states that are no graph vertex, joined to the graph
by the prior domain's motions). Every policy meets the query as new: the planner forgets the libraries and
trees it built for earlier queries before each plan (:meth:`Planner.forget_queries
<drd_planner.planner.Planner.forget_queries>`), and the graph baselines join an off-graph state themselves
(:meth:`Planner.query_graph <drd_planner.planner.Planner.query_graph>`), all inside the timed call.

Policies:

- the Planner's library policies (``direct_bisect``, ``bisect``, ...): :meth:`Planner.plan`, graph stage and
  growth included;
- ``lazysp``: LazySP (forward selector, no check cap) on the query's graph;
- ``check_all``: every edge of the query's graph checked, then the shortest free path. Its checks of the
  prior's E edges do not depend on the query, so they are made (and timed) once per world
  (:func:`full_row`, batched) and charged to each of its queries, with ``E x C`` ms added for the check cost
  instead of busy-waiting it E times; a joined query's motions are checked in the episode, at cost C.

A plan counts as **verified** only when every edge of its path was checked free in that episode.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drd_planner.arrays import BoolArray, FloatArray
from drd_planner.bench.check_cost import Timed, timed, with_check_cost
from drd_planner.core.episode import EdgeOracle, run_episode
from drd_planner.core.lazysp import GraphArcs, LazySP, LazySPSettings
from drd_planner.planner.planner import Planner
from drd_planner.planner.query_graph import MotionDispatch, QueryGraph
from drd_planner.planner.query_library import ShortestPaths

__all__ = [
    "LEAD_POLICY",
    "QUERY_KINDS",
    "CostQuery",
    "EpisodeTime",
    "FullRow",
    "check_all_episode",
    "full_row",
    "lazysp_episode",
    "plan_episode",
]

#: ``direct_bisect`` with the planner told each episode's check cost (:meth:`Planner.check_cost_ms`).
LEAD_POLICY = "direct_bisect_lead"
#: The query kinds, in report order.
QUERY_KINDS: tuple[str, ...] = ("stored", "new", "off_graph")


@dataclass(frozen=True)
class CostQuery:
    """One benchmark query.

    Attributes:
        kind: one of :data:`QUERY_KINDS`.
        start: a vertex id, or a (D,) state off the graph.
        goal: likewise.
        world: the index of the world it runs against (in the caller's list of worlds).
    """

    kind: str
    start: int | FloatArray
    goal: int | FloatArray
    world: int


@dataclass(frozen=True)
class EpisodeTime:
    """One policy on one query at one check cost.

    Attributes:
        policy: the policy's name.
        query: the query's index.
        kind: the query's kind.
        cost_ms: the added CPU per check (ms).
        verified: a path was returned and its every edge was checked free in this episode.
        checks: checks made (edges and motions).
        time: CPU and wall time to the end of the episode (ms), checks and their cost included.
    """

    policy: str
    query: int
    kind: str
    cost_ms: float
    verified: bool
    checks: int
    time: Timed


@dataclass(frozen=True)
class FullRow:
    """``check_all``'s checks of one world: the (E,) outcomes (True = free) and their time at cost 0."""

    outcomes: BoolArray
    time: Timed


def full_row(oracle: EdgeOracle, num_edges: int) -> FullRow:
    """Check every edge ``0..num_edges-1`` with ``oracle``, timed.

    Batched when it has ``check_many`` (a domain's edge checker: how checking everything is done), else one
    by one.
    """

    def run() -> BoolArray:
        many = getattr(oracle, "check_many", None)
        if many is not None:
            return np.asarray(many(np.arange(num_edges)), dtype=bool)
        return np.array([bool(oracle.check(e)) for e in range(num_edges)], dtype=bool)

    outcomes, spent = timed(run)
    return FullRow(outcomes, spent)


def _checked_free(edges: list[int], log: dict[int, bool]) -> bool:
    return len(edges) > 0 and all(log.get(e) is True for e in edges)


def plan_episode(
    planner: Planner, query: CostQuery, index: int, oracle: EdgeOracle, cost_ms: float, policy: str, seed: int
) -> EpisodeTime:
    """``policy`` through :meth:`Planner.plan` (the query new to the planner).

    :data:`LEAD_POLICY` is ``direct_bisect`` with the planner told the check cost (``check_cost_ms = C``: a
    new query's lead, :mod:`~drd_planner.planner.lead`); every other policy plans with it unknown.
    """
    planner.forget_queries()
    costly = with_check_cost(oracle, cost_ms)
    told = policy == LEAD_POLICY
    planner.check_cost_ms = cost_ms if told else None
    plan_policy = "direct_bisect" if told else policy
    try:
        result, spent = timed(lambda: planner.plan(query.start, query.goal, costly, seed=seed, policy=plan_policy))
    finally:
        planner.check_cost_ms = None
    edges = [int(e) for e in result.edges] if result.found else []
    verified = result.found and _checked_free(edges, result.outcomes())
    return EpisodeTime(policy, index, query.kind, cost_ms, verified, costly.checks, spent)


def _target(query: QueryGraph, costly: EdgeOracle) -> EdgeOracle:
    """The oracle of a query's graph: graph edges by id, joined motions by their states."""
    if not query.connected:
        return costly
    return MotionDispatch(costly, query.motions)  # type: ignore[arg-type]


def lazysp_episode(planner: Planner, query: CostQuery, index: int, oracle: EdgeOracle, cost_ms: float) -> EpisodeTime:
    """LazySP (forward selector, no check cap) on the query's graph (joins made in the timed call)."""
    costly = with_check_cost(oracle, cost_ms)

    def run() -> list[int]:
        graph_query = planner.query_graph(query.start, query.goal)
        graph = graph_query.graph
        search = LazySP(graph, graph_query.start, graph_query.goal, LazySPSettings(max_checks=None))
        episode = run_episode(None, graph.lengths, search, _target(graph_query, costly))
        if not episode.success or episode.path_edges is None:
            return []
        log = {c.edge: c.free for c in episode.checks}
        edges = [int(e) for e in episode.path_edges]
        return edges if _checked_free(edges, log) else []

    edges, spent = timed(run)
    return EpisodeTime("lazysp", index, query.kind, cost_ms, bool(edges), costly.checks, spent)


def check_all_episode(
    planner: Planner, query: CostQuery, index: int, oracle: EdgeOracle, cost_ms: float, row: FullRow
) -> EpisodeTime:
    """``check_all``: the world's :class:`FullRow` (plus E x C ms), the joined motions, then Dijkstra."""
    costly = with_check_cost(oracle, cost_ms)
    num_edges = row.outcomes.size

    def run() -> bool:
        graph_query = planner.query_graph(query.start, query.goal)
        graph = graph_query.graph
        target = _target(graph_query, costly)
        extra = [bool(target.check(e)) for e in range(num_edges, graph.num_edges)]
        outcomes = np.concatenate([row.outcomes, np.array(extra, dtype=bool)])
        path = ShortestPaths(GraphArcs(graph), graph.lengths).path(graph_query.start, graph_query.goal, outcomes)
        return path is not None

    found, spent = timed(run)
    waited = Timed(num_edges * cost_ms, num_edges * cost_ms)
    checks = num_edges + costly.checks
    return EpisodeTime("check_all", index, query.kind, cost_ms, found, checks, row.time + spent + waited)
