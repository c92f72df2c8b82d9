"""Straight joint-space (or planar) segments joining an off-graph state to its nearest graph vertices."""

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

__all__ = ["StraightConnector", "straight_connector"]


class StraightConnector:
    """Straight segments in the state space to the nearest vertices (arm joint space, planar xy).

    Args:
        neighbours: vertices joined, at most.
        reach: the farthest vertex joined (state units).
        resolution: largest step between the samples of a motion (state units).
    """

    def __init__(self, *, neighbours: int = DEFAULT_NEIGHBOURS, reach: float, resolution: float) -> None:
        if neighbours < 1 or not (reach > 0 and resolution > 0 and math.isfinite(reach + resolution)):
            raise ProblemError("a connector needs neighbours >= 1 and finite positive reach and resolution")
        self._k = int(neighbours)
        self._reach = float(reach)
        self._resolution = float(resolution)
        self._nearest = NearestVertices()

    @property
    def reach(self) -> float:
        """The farthest vertex joined."""
        return self._reach

    @property
    def position_dims(self) -> int:
        """Every dimension is a position (joint angles or coordinates)."""
        return 10**6

    def connect(self, state: FloatArray, graph: ExplicitGraph, *, outgoing: bool) -> list[Motion]:
        """Segments to (or from) the nearest vertices within reach."""
        states = vertex_states_of(graph)
        out = []
        for d, v in self._nearest.query(graph, state, self._k, self._reach):
            n = max(2, math.ceil(d / self._resolution) + 1)
            line = np.linspace(state, states[v], n)
            out.append(Motion(int(v), line if outgoing else line[::-1].copy(), float(d)))
        return out


def straight_connector(prior: WorldPrior) -> StraightConnector | None:
    """Segments no longer than the graph's longest edge, sampled at the domain's check resolution."""
    graph = prior.graph
    if graph.vertex_states is None or graph.num_edges == 0:
        return None
    resolution = prior.domain_spec.get("resolution")
    if not isinstance(resolution, int | float) or not resolution > 0:
        resolution = float(np.median(graph.lengths)) / POINTS_PER_EDGE
    return StraightConnector(reach=float(graph.lengths.max()), resolution=float(resolution))
