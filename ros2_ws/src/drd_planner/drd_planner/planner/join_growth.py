"""More joins when the first do not suffice: an off-graph start or goal joined to more vertices, lazily.

A state off the graph is joined by its connector's first few motions (the helicopter's 16 shortest flyable
ones, :class:`~drd_planner.planner.dubins_connector.DubinsConnector`). When every path through them is
blocked - a wire or a no-fly zone right ahead, a state low in a valley whose short motions all run into the
terrain - the graph can still have a free path through a motion that was not among the first. Then, round
after round (the loop of :class:`~drd_planner.planner.roadmap_growth.GraphGrowth`), the start and the goal get
their next joins (as many again as they have, at least ``join_batch``: 64, 128, 256, ...), each new motion an
ordinary lazy edge with its imputed prior, and the lazy graph search runs again reusing every outcome. The
rounds begin once the graph stage has made ``graph_checks_first`` checks (64) without a verified path, not only
after it has proved that no path through the first joins is free: on ``heli_lines`` starts 150 m off the
lattice whose first joins lead into parts of the lattice walled off from the goal made 171-1569 checks (0.6-3.3 s)
before more joins began, while a join further down the ranking (often straight to the goal) was free; with the
rounds begun after 64 checks most of them needed 67-83.

Which joins come next is decided by the prior, not by length alone: when the connector can sketch its motions
in bulk (:class:`SketchedJoins`: a few points along each, vectorised), candidate joins are imputed from the
training worlds and the ranking is reordered by the lazy search's own weight, -log theta + lambda * length
(:class:`~drd_planner.planner.join_ranking.PriorRanking`: imputed in the connector's order only as far as a
round needs, in the same order as imputing them all). On ``heli_lines`` a start low in a valley (every join among
the 600 shortest blocked) and a goal whose short joins lead into a blocked part of the lattice needed 1071 and
2100 checks (7-13 s) with joins offered by length in rounds of 16, 32, 64, ...; ordered by the prior, 44 and 33.

Only joins that can still lead somewhere are offered: a start is joined only to vertices from which the goal
can still be reached over edges not known blocked, a goal only from vertices the start can still reach (one
breadth-first search each round). So a goal cut off from everything stops the growth at once instead of
joining the start to every vertex. It stops at the first verified path, when no such vertex is left in the
ranking (the planner's "no path" is then exact for single-motion joins), or at a budget
(:class:`~drd_planner.planner.roadmap_growth.GrowthSettings`: ``max_joins`` per state, none by default,
rounds, seconds, checks, and the plan's own).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np
from scipy.sparse import csr_array
from scipy.sparse.csgraph import breadth_first_order

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.episode import CheckRecord
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.world_columns import WorldColumns
from drd_planner.planner.connect import POINTS_PER_EDGE, EdgeSampleIndex, MotionOracle, VertexJoins
from drd_planner.planner.join_ranking import PriorRanking
from drd_planner.planner.prior import WorldPrior
from drd_planner.planner.query_graph import QueryGraph
from drd_planner.planner.roadmap_growth import DEFAULT_GROWTH, GraphGrowth, GrowthLimits, GrowthSettings

__all__ = ["JoinGrowth", "MoreJoins", "SketchedJoins", "more_joins_of", "still_open"]


@runtime_checkable
class MoreJoins(VertexJoins, Protocol):
    """A connector that ranks every vertex it could join a state to, and joins any of them."""

    @property
    def neighbours(self) -> int:
        """How many of the ranking its ``connect`` joins (the first ones)."""
        ...

    def ranked(self, state: FloatArray, graph: ExplicitGraph, *, outgoing: bool) -> IntArray:
        """(M,) the vertices a motion joins to ``state``, best first."""
        ...


@runtime_checkable
class SketchedJoins(Protocol):
    """A connector that sketches many joining motions at once (a few points each), for ranking by the prior."""

    def sketches(
        self,
        state: FloatArray,
        graph: ExplicitGraph,
        vertices: IntArray,
        *,
        outgoing: bool,
        fractions: FloatArray,
    ) -> tuple[FloatArray, FloatArray]:
        """(M,) lengths and (M, P, D') positions at the arc-length ``fractions`` (P,) of each joining motion."""
        ...


def more_joins_of(connector: object) -> MoreJoins | None:
    """The connector when it offers more joins (:class:`MoreJoins`), else None."""
    return connector if isinstance(connector, MoreJoins) else None


def still_open(
    edges: IntArray, num_vertices: int, open_edges: BoolArray, source: int, *, directed: bool, reverse: bool
) -> BoolArray:
    """(V,) the vertices reachable from ``source`` (that reach it when ``reverse``) over the ``open_edges``.

    Args:
        edges: (E, 2) vertex ids.
        num_vertices: V.
        open_edges: (E,) the edges that may be used (those not known blocked).
        source: where the search starts.
        directed: whether edges go only from their first vertex to their second.
        reverse: search against the edges' direction.
    """
    u, v = edges[open_edges, 0], edges[open_edges, 1]
    if not directed:
        u, v = np.concatenate([u, v]), np.concatenate([v, u])
    if reverse:
        u, v = v, u
    adjacency = csr_array((np.ones(u.size), (u, v)), shape=(num_vertices, num_vertices))
    out = np.zeros(num_vertices, dtype=bool)
    out[breadth_first_order(adjacency, source, directed=True, return_predecessors=False)] = True
    return out


class JoinGrowth(GraphGrowth):
    """Gives an off-graph start and goal more joins each round (see the module docstring).

    It may begin before the graph stage has proved the first joins insufficient
    (:attr:`~drd_planner.planner.roadmap_growth.GraphGrowth.starts_early`): a join further down the ranking
    is often a far shorter way out than the proof that none through the first joins is free.

    Args:
        prior: the prior (its graph is what the connector ranks, its worlds impute the new edges).
        query: the query's graph after the graph stage found no path.
        connector: the connector that joined the states.
        index: points along the prior's graph edges (for the imputation).
        settings: the budget (``max_joins`` per state).
        columns: the training worlds as packed columns (faster imputation of the ranked joins), when at hand.
    """

    starts_early = True

    def __init__(
        self,
        prior: WorldPrior,
        query: QueryGraph,
        connector: MoreJoins,
        index: EdgeSampleIndex,
        settings: GrowthSettings = DEFAULT_GROWTH,
        columns: WorldColumns | None = None,
    ) -> None:
        super().__init__(prior, query, index, settings)
        self.connector = connector
        #: Per off-graph endpoint (its query vertex): its state, whether it is the start, and its ranking.
        self.ends: dict[int, tuple[FloatArray, bool, PriorRanking]] = {}
        #: Per off-graph endpoint: the prior's vertices it is joined to so far.
        self.joined: dict[int, set[int]] = {}
        for vertex, state in sorted(query.new_states.items()):
            if vertex not in (query.start, query.goal):
                continue
            outgoing = vertex == query.start
            array = np.asarray(state, dtype=np.float64)
            given = connector.ranked(array, prior.graph, outgoing=outgoing)
            if isinstance(connector, SketchedJoins) and prior.worlds is not None:
                lengths, points = connector.sketches(
                    array,
                    prior.graph,
                    given,
                    outgoing=outgoing,
                    fractions=np.linspace(0, 1, POINTS_PER_EDGE),
                )
                ranking = PriorRanking.of_prior(given, lengths, points, index, prior, columns)
            else:  # nothing to weigh the joins by: the connector's order
                ranking = PriorRanking.as_given(given)
            self.ends[vertex] = (array, outgoing, ranking)
            edges = query.graph.edges
            mine = edges[:, 0] == vertex if outgoing else edges[:, 1] == vertex
            self.joined[vertex] = set((edges[mine, 1] if outgoing else edges[mine, 0]).tolist())

    def _grow(
        self,
        rng: np.random.Generator,
        oracle: MotionOracle,
        known: dict[int, bool],
        checks: list[CheckRecord],
        limits: GrowthLimits,
    ) -> bool:
        """As many joins again for each off-graph endpoint, to vertices that can still lead to the other end.

        False when no endpoint has such a vertex left in its ranking (or its ``max_joins`` is reached).
        """
        grown, base = self.grown, self.grown.base
        open_edges = np.ones(grown.edges.shape[0], dtype=bool)
        open_edges[[e for e, free in known.items() if not free]] = False
        added = False
        for vertex, (state, outgoing, ranking) in self.ends.items():
            joined = self.joined[vertex]
            cap = self.settings.max_joins
            room = ranking.size if cap is None else cap - len(joined)
            if room <= 0:
                continue
            other = base.goal if outgoing else base.start
            useful = still_open(
                grown.edges,
                grown.num_vertices,
                open_edges,
                other,
                directed=base.graph.directed,
                reverse=outgoing,
            )
            batch = ranking.size if self.settings.join_batch is None else max(len(joined), self.settings.join_batch)
            take = _next_joins(ranking, min(batch, room), useful, joined)
            if take.size == 0:
                continue
            motions = self.connector.motions_to(state, self.prior.graph, take, outgoing=outgoing)
            joined.update(int(v) for v in take.tolist())
            if not motions:
                continue
            pairs = np.array([(vertex, m.vertex) if outgoing else (m.vertex, vertex) for m in motions], dtype=np.int64)
            lengths = np.array([m.length for m in motions], dtype=np.float64)
            grown.add_edges(pairs, [m.states for m in motions], lengths)
            added = True
        return added


def _next_joins(ranking: PriorRanking, count: int, useful: BoolArray, joined: set[int]) -> IntArray:
    """(k <= count,) the first ``count`` vertices of ``ranking`` that are ``useful`` (V,) and not ``joined`` yet.

    The ranking is imputed no further than they need.
    """
    asked = count
    while True:
        head = ranking.first(asked)
        fresh = [v for v in head.tolist() if useful[v] and v not in joined]
        if len(fresh) >= count or head.size >= ranking.size:
            return np.array(fresh[:count], dtype=np.int64)
        asked = head.size + count - len(fresh)
