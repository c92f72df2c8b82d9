"""More joins when the first do not suffice: an off-graph start or goal joined to more vertices, lazily.

A state off the graph is joined by its connector's first few motions (the helicopter's 16 shortest flyable
ones, :class:`~drd_planner.planner.dubins_connector.DubinsConnector`). When every path through them is
blocked - a wire or a no-fly zone right ahead, a state facing away from the lattice whose short motions all
loop through an obstacle - the graph can still have a free path through a motion that was not among the
first. Then, round after round (the loop of :class:`~drd_planner.planner.roadmap_growth.GraphGrowth`), the
start and the goal get their next joins in the connector's own ranking (:meth:`more_motions`: as many again
as they have, so 16, 32, 64, ...), each new motion an ordinary lazy edge with its imputed prior, and the
lazy graph search runs again reusing every outcome. It stops at the first verified path, when the ranking is
exhausted (every vertex a flyable motion reaches was offered: the planner's "no path" is then exact for
single-motion joins), or at a budget (:class:`~drd_planner.planner.roadmap_growth.GrowthSettings`:
``max_joins`` per state, rounds, seconds, checks, and the plan's own).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.core.episode import CheckRecord
from drd_planner.core.graph import ExplicitGraph
from drd_planner.planner.connect import EdgeSampleIndex, Motion, MotionOracle
from drd_planner.planner.prior import WorldPrior
from drd_planner.planner.query_graph import QueryGraph
from drd_planner.planner.roadmap_growth import DEFAULT_GROWTH, GraphGrowth, GrowthLimits, GrowthSettings

__all__ = ["JoinGrowth", "MoreJoins", "more_joins_of"]


@runtime_checkable
class MoreJoins(Protocol):
    """A connector that can join a state to more vertices than its first ones, in a fixed ranking."""

    @property
    def neighbours(self) -> int:
        """How many motions its ``connect`` gives at most (the first of the ranking)."""
        ...

    def more_motions(
        self, state: FloatArray, graph: ExplicitGraph, *, outgoing: bool, skip: int, count: int
    ) -> list[Motion]:
        """The motions to the next ``count`` ranked vertices after the first ``skip``."""
        ...


def more_joins_of(connector: object) -> MoreJoins | None:
    """The connector when it offers more joins (:class:`MoreJoins`), else None."""
    return connector if isinstance(connector, MoreJoins) else None


class JoinGrowth(GraphGrowth):
    """Gives an off-graph start and goal more joins each round (see the module docstring).

    Args:
        prior: the prior (its graph is what the connector ranks, its worlds impute the new edges).
        query: the query's graph after the graph stage found no path.
        connector: the connector that joined the states.
        index: points along the prior's graph edges (for the imputation).
        settings: the budget (``max_joins`` per state).
    """

    def __init__(
        self,
        prior: WorldPrior,
        query: QueryGraph,
        connector: MoreJoins,
        index: EdgeSampleIndex,
        settings: GrowthSettings = DEFAULT_GROWTH,
    ) -> None:
        super().__init__(prior, query, index, settings)
        self.connector = connector
        #: Per off-graph endpoint (its query vertex): (state, outgoing, joins offered so far).
        self.offered: dict[int, tuple[FloatArray, bool, int]] = {
            vertex: (np.asarray(state, dtype=np.float64), vertex == query.start, connector.neighbours)
            for vertex, state in query.new_states.items()
            if vertex in (query.start, query.goal)
        }
        self.exhausted: set[int] = set()

    def _grow(
        self,
        rng: np.random.Generator,
        oracle: MotionOracle,
        known: dict[int, bool],
        checks: list[CheckRecord],
        limits: GrowthLimits,
    ) -> bool:
        """The next joins of each off-graph endpoint (as many again as it has); False when none is left."""
        added = False
        for vertex, (state, outgoing, offered) in sorted(self.offered.items()):
            if vertex in self.exhausted:
                continue
            count = min(offered, self.settings.max_joins - offered)
            motions = self.connector.more_motions(
                state, self.prior.graph, outgoing=outgoing, skip=offered, count=max(count, 0)
            )
            self.offered[vertex] = (state, outgoing, offered + max(count, 0))
            if len(motions) < count or count <= 0 or offered + count >= self.settings.max_joins:
                self.exhausted.add(vertex)
            if not motions:
                continue
            pairs = np.array(
                [(vertex, m.vertex) if outgoing else (m.vertex, vertex) for m in motions], dtype=np.int64
            )
            lengths = np.array([m.length for m in motions], dtype=np.float64)
            self.grown.add_edges(pairs, [m.states for m in motions], lengths)
            added = True
        return added
