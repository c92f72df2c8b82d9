"""The graph one query plans over: the prior's own, or the prior's plus new motions to off-graph states."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.status import PlanCause
from drd_planner.core.world_columns import WorldColumns
from drd_planner.planner.connect import (
    EdgeSampleIndex,
    Motion,
    MotionOracle,
    QueryConnector,
    VertexJoins,
    imputed_columns,
)
from drd_planner.planner.endpoints import QueryError
from drd_planner.planner.prior import WorldPrior
from drd_planner.planner.query_worlds import QueryWorlds


@dataclass(frozen=True)
class Joins:
    """The motions joining an off-graph start or goal to the graph.

    Attributes:
        vertices: (k,) the graph vertex at each motion's other end.
        lengths: (k,) their lengths (the graph's unit).
        edges: (k,) their edge ids in the query's graph.
        free: (n, k) bool: each motion's imputed outcome in each training world (None without worlds).
    """

    vertices: IntArray
    lengths: FloatArray
    edges: IntArray
    free: BoolArray | None


@dataclass(frozen=True)
class QueryGraph:
    """Graph, training worlds and check costs of one query.

    Attributes:
        graph: the prior's graph, plus a new vertex per off-graph state (ids from V on) and its motions
            (edge ids from E on).
        worlds: the (n, E') training outcomes, the new edges' imputed (:func:`imputed_outcomes`) beside the
            prior's (never a copy of them); None for a prior without worlds over every edge.
        edge_costs: (E',) check costs (a new edge costs the median of the graph's).
        start: start vertex id.
        goal: goal vertex id.
        motions: new edge id -> (K, D) states along it, tail first.
        new_states: new vertex id -> its (D,) state.
        start_joins: the motions joining an off-graph start (None when the start is a graph vertex).
        goal_joins: the motions joining an off-graph goal (None when the goal is a graph vertex).
    """

    graph: ExplicitGraph
    worlds: QueryWorlds | None
    edge_costs: FloatArray
    start: int
    goal: int
    motions: Mapping[int, FloatArray] = field(default_factory=dict)
    new_states: Mapping[int, FloatArray] = field(default_factory=dict)
    start_joins: Joins | None = None
    goal_joins: Joins | None = None

    @property
    def connected(self) -> bool:
        """True when the query added vertices and motions to the prior's graph."""
        return bool(self.motions)


def prior_query(prior: WorldPrior, start: int, goal: int, columns: WorldColumns | None) -> QueryGraph:
    """A query between two graph vertices: the prior's own graph and worlds (no copy)."""
    worlds = None if prior.worlds is None or columns is None else QueryWorlds(prior.worlds, columns)
    return QueryGraph(prior.graph, worlds, prior.edge_costs, start, goal)


def connected_query(
    prior: WorldPrior,
    start: int | FloatArray,
    goal: int | FloatArray,
    connector: QueryConnector,
    index: EdgeSampleIndex,
    columns: WorldColumns | None,
) -> QueryGraph:
    """Join the off-graph start and/or goal state to the graph with the connector's motions.

    With a connector that joins any vertex (:class:`~drd_planner.planner.connect.VertexJoins`), an off-graph
    state whose other end is a vertex is also joined straight to that vertex when a motion can (once: not
    again when it is among the state's nearest joins).

    Raises:
        QueryError: no vertex within the connector's reach of a state.
    """
    graph = prior.graph
    states = graph.vertex_states
    assert states is not None
    new_edges: list[tuple[int, int]] = []
    motions: list[Motion] = []
    new_states: dict[int, FloatArray] = {}
    ends: dict[str, int] = {}
    spans: dict[str, tuple[int, int]] = {}
    next_vertex = graph.num_vertices
    for label, value in (("start", start), ("goal", goal)):
        if isinstance(value, int):
            ends[label] = value
            continue
        found = connector.connect(value, graph, outgoing=label == "start")
        other = goal if label == "start" else start
        if isinstance(other, int) and isinstance(connector, VertexJoins) and other not in {m.vertex for m in found}:
            # the motion straight to (from) the query's other end: often the whole plan of a robot off the graph
            found = found + connector.motions_to(value, graph, np.array([other]), outgoing=label == "start")
        if not found:
            raise QueryError(
                f"{label} state {np.round(value, 4).tolist()} has no graph vertex within the connection reach "
                f"{connector.reach:.4g} that a motion can join: outside the graph's reach",
                cause=PlanCause.outside(label),
            )
        vertex = next_vertex
        next_vertex += 1
        new_states[vertex] = np.asarray(value, dtype=np.float64)
        ends[label] = vertex
        spans[label] = (len(motions), len(motions) + len(found))
        for m in found:
            new_edges.append((vertex, m.vertex) if label == "start" else (m.vertex, vertex))
            motions.append(m)
    num_edges = graph.num_edges
    edges = np.vstack([graph.edges, np.array(new_edges, dtype=np.int64).reshape(-1, 2)])
    lengths = np.concatenate([graph.lengths, [m.length for m in motions]])
    extra = np.array([new_states[v] for v in sorted(new_states)], dtype=np.float64).reshape(-1, states.shape[1])
    query_graph = ExplicitGraph(edges, lengths, next_vertex, graph.directed, np.vstack([states, extra]))
    worlds: QueryWorlds | None = None
    imputed: BoolArray | None = None
    if prior.worlds is not None and columns is not None:
        imputed = imputed_columns(index, columns, [m.states for m in motions])
        worlds = QueryWorlds(prior.worlds, columns, imputed)
    cost = float(np.median(prior.edge_costs))
    costs = np.concatenate([prior.edge_costs, np.full(len(motions), cost)])
    by_edge = {num_edges + i: m.states for i, m in enumerate(motions)}
    joins = {
        label: Joins(
            np.array([m.vertex for m in motions[a:b]], dtype=np.int64),
            np.array([m.length for m in motions[a:b]], dtype=np.float64),
            np.arange(num_edges + a, num_edges + b, dtype=np.int64),
            None if imputed is None else imputed[:, a:b],
        )
        for label, (a, b) in spans.items()
    }
    return QueryGraph(
        query_graph,
        worlds,
        costs,
        ends["start"],
        ends["goal"],
        by_edge,
        new_states,
        joins.get("start"),
        joins.get("goal"),
    )


class MotionDispatch:
    """The edge oracle of a connected query: graph edges to ``check``, new motions to ``check_motion``."""

    def __init__(self, oracle: MotionOracle, motions: Mapping[int, FloatArray]) -> None:
        self._oracle = oracle
        self._motions = motions

    @property
    def oracle(self) -> MotionOracle:
        """The wrapped oracle (graph edges and motions by their states)."""
        return self._oracle

    def check(self, edge: int) -> bool:
        """True when ``edge`` (a graph edge or a new motion) is free."""
        states = self._motions.get(int(edge))
        if states is None:
            return bool(self._oracle.check(edge))
        return bool(self._oracle.check_motion(states))
