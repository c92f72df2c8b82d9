"""Helicopter motions joining an off-graph (x, y, z, heading) state to the lattice: Dubins curves, altitude linear."""

from __future__ import annotations

import math

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.domains.dubins import dubins_path
from drd_planner.exceptions import ProblemError
from drd_planner.planner.connect import DEFAULT_NEIGHBOURS, Motion, NearestVertices, vertex_states_of
from drd_planner.planner.prior import WorldPrior

__all__ = ["DubinsConnector", "dubins_connector"]


class DubinsConnector:
    """Helicopter motions: a Dubins curve in the plane, altitude linear along it ((x, y, z, heading) states).

    Args:
        turning_radius: metres.
        neighbours: vertices joined, at most (nearest in x, y, z).
        reach: the farthest vertex joined, metres (x, y, z).
        spacing: largest arc-length step between samples, metres.
        max_climb_gradient: largest |dz| / horizontal length of a motion.
    """

    def __init__(
        self,
        *,
        turning_radius: float,
        neighbours: int = DEFAULT_NEIGHBOURS,
        reach: float,
        spacing: float,
        max_climb_gradient: float = 0.5,
    ) -> None:
        if not (turning_radius > 0 and reach > 0 and spacing > 0 and max_climb_gradient > 0):
            raise ProblemError("a Dubins connector needs positive radius, reach, spacing and climb gradient")
        self._radius = float(turning_radius)
        self._k = int(neighbours)
        self._reach = float(reach)
        self._spacing = float(spacing)
        self._climb = float(max_climb_gradient)
        self._nearest = NearestVertices(dims=3)

    @property
    def reach(self) -> float:
        """The farthest vertex joined, metres."""
        return self._reach

    @property
    def position_dims(self) -> int:
        """x, y, z."""
        return 3

    def connect(self, state: FloatArray, graph: ExplicitGraph, *, outgoing: bool) -> list[Motion]:
        """Dubins motions to (or from) the nearest vertices within reach that the climb limit allows."""
        states = vertex_states_of(graph)
        if states.shape[1] != 4 or state.shape != (4,):
            raise ProblemError("helicopter states are (x, y, z, heading)")
        out: list[Motion] = []
        # Vertices differ by heading at one position: look at more of them than will be joined.
        for _, v in self._nearest.query(graph, state[:3], self._k * 3, self._reach):
            if len(out) >= self._k:
                break
            tail, head = (state, states[v]) if outgoing else (states[v], state)
            path = dubins_path((tail[0], tail[1], tail[3]), (head[0], head[1], head[3]), radius=self._radius)
            horizontal = path.length
            dz = float(head[2] - tail[2])
            if horizontal <= 0 or abs(dz) > self._climb * horizontal or horizontal > 4 * self._reach:
                continue
            n = max(2, math.ceil(horizontal / self._spacing) + 1)
            s = np.linspace(0.0, horizontal, n)
            pose = path.sample(s)
            samples = np.column_stack([pose[:, 0], pose[:, 1], tail[2] + dz * s / horizontal, pose[:, 2]])
            out.append(Motion(int(v), samples, math.hypot(horizontal, dz)))
        return out


def dubins_connector(prior: WorldPrior) -> DubinsConnector | None:
    """The connector of a helicopter prior (None when its graph has no (x, y, z, heading) states)."""
    lattice = prior.domain_spec.get("lattice") or {}
    graph = prior.graph
    if graph.vertex_states is None or graph.vertex_states.shape[1] != 4:
        return None
    return DubinsConnector(
        turning_radius=float(lattice.get("turning_radius", 100.0)),
        reach=2.0 * float(lattice.get("xy_spacing", 50.0)),
        spacing=float(lattice.get("sample_spacing", 5.0)),
        max_climb_gradient=float(lattice.get("max_climb_gradient", 0.5)),
    )
