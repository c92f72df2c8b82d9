"""Straight joint-space (or planar) segments joining an off-graph state to its nearest graph vertices.

A connector may carry the domain's :class:`~drd_planner.planner.state_sampler.StateSampler` (the arm's:
statically valid configurations), which lets the planner grow the roadmap with the same straight motions
(:meth:`StraightConnector.segment`, sampled at the check resolution).
"""

from __future__ import annotations

import math

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.exceptions import ProblemError
from drd_planner.planner.connect import (
    DEFAULT_NEIGHBOURS,
    POINTS_PER_EDGE,
    Motion,
    NearestVertices,
    vertex_states_of,
)
from drd_planner.planner.prior import WorldPrior
from drd_planner.planner.state_sampler import StateSampler

__all__ = ["StraightConnector", "straight_connector"]


class StraightConnector:
    """Straight segments in the state space to the nearest vertices (arm joint space, planar xy).

    Args:
        neighbours: vertices joined, at most.
        reach: the farthest vertex joined (state units).
        resolution: largest step between the samples of a motion (state units).
        sampler: the domain's valid states (None: the planner does not grow the graph).
    """

    def __init__(
        self,
        *,
        neighbours: int = DEFAULT_NEIGHBOURS,
        reach: float,
        resolution: float,
        sampler: StateSampler | None = None,
    ) -> None:
        if neighbours < 1 or not (reach > 0 and resolution > 0 and math.isfinite(reach + resolution)):
            raise ProblemError("a connector needs neighbours >= 1 and finite positive reach and resolution")
        self._k = int(neighbours)
        self._reach = float(reach)
        self._resolution = float(resolution)
        self._nearest = NearestVertices()
        self.sampler = sampler

    @property
    def reach(self) -> float:
        """The farthest vertex joined."""
        return self._reach

    @property
    def position_dims(self) -> int:
        """Every dimension is a position (joint angles or coordinates)."""
        return 10**6

    @property
    def resolution(self) -> float:
        """Largest step between consecutive samples of a motion (state units, Euclidean)."""
        return self._resolution

    def segment(self, tail: FloatArray, head: FloatArray) -> FloatArray:
        """(K, D) samples of the straight motion from ``tail`` to ``head``, both included, K >= 2.

        Consecutive samples are at most :attr:`resolution` apart (Euclidean distance).
        """
        a, b = np.asarray(tail, dtype=np.float64), np.asarray(head, dtype=np.float64)
        n = max(2, math.ceil(float(np.linalg.norm(b - a)) / self._resolution) + 1)
        return np.linspace(a, b, n)

    def connect(self, state: FloatArray, graph: ExplicitGraph, *, outgoing: bool) -> list[Motion]:
        """Segments to (or from) the nearest vertices within reach."""
        states = vertex_states_of(graph)
        out = []
        for d, v in self._nearest.query(graph, state, self._k, self._reach):
            line = self.segment(state, states[v])
            out.append(Motion(int(v), line if outgoing else line[::-1].copy(), float(d)))
        return out


def straight_connector(prior: WorldPrior, *, sampler: StateSampler | None = None) -> StraightConnector | None:
    """Segments no longer than the graph's longest edge, sampled at the domain's check resolution.

    ``sampler``: the domain's valid states, for roadmap growth (None: no growth).
    """
    graph = prior.graph
    if graph.vertex_states is None or graph.num_edges == 0:
        return None
    resolution = prior.domain_spec.get("resolution")
    if not isinstance(resolution, int | float) or not resolution > 0:
        resolution = float(np.median(graph.lengths)) / POINTS_PER_EDGE
    return StraightConnector(reach=float(graph.lengths.max()), resolution=float(resolution), sampler=sampler)
