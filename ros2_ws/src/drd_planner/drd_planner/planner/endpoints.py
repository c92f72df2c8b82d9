"""A query's start and goal: vertex ids, or states snapped to the nearest graph vertex.

A state is a (d,) vector in the graph's vertex-state space (helicopter: x, y, z in metres and heading
in radians; arm: joint angles in radians; planar: x, y). It resolves to the nearest vertex by
Euclidean distance in that space when the distance is within the snap tolerance; anything else is
refused with the distance and the tolerance named.

A goal may leave some dimensions free (``free_goal_dims``; the helicopter's heading): NaN there, or a goal
given without its trailing free dimensions (a helicopter goal of three values, x, y, z), means "any value".
Such a goal never snaps to a vertex: the connector joins it (the helicopter arrives with any heading).
"""

from __future__ import annotations

import numbers

import numpy as np
import numpy.typing as npt
from scipy.spatial import cKDTree

from drd_planner.arrays import FloatArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.status import PlanCause
from drd_planner.exceptions import DrdError, PlanningError

#: Default snap tolerance as a fraction of the median edge length.
SNAP_FRACTION_OF_EDGE = 0.25

Endpoint = int | npt.ArrayLike

#: A query as given on the command line: the start's and the goal's text (a vertex id, or a state's numbers).
QueryText = tuple[str, str]


def endpoint_value(text: str) -> int | FloatArray:
    """A vertex id (one integer) or a (d,) state (several numbers, separated by spaces or ';') from its text.

    Raises:
        DrdError: text that is neither.
    """
    fields = text.replace(";", " ").split()
    try:
        if len(fields) == 1 and fields[0].lstrip("-").isdigit():
            return int(fields[0])
        return np.array([float(f) for f in fields], dtype=np.float64)
    except ValueError:
        raise DrdError(f"{text!r} is neither a vertex id nor a state of numbers") from None


class QueryError(PlanningError):
    """A start or goal that cannot be served (malformed, outside the graph, or out of reach).

    Args:
        message: why, in words.
        cause: the cause as a value, where it is one of :class:`PlanCause` (an end outside the graph).
    """

    def __init__(self, message: str, *, cause: PlanCause | None = None) -> None:
        super().__init__(message)
        self.cause = cause


class EndpointResolver:
    """Turns vertex ids and states into vertex ids of one graph.

    Args:
        graph: the graph (its ``vertex_states`` are needed for states).
        snap_tolerance: the farthest a state may be from its vertex, in state units; None uses
            :data:`SNAP_FRACTION_OF_EDGE` x the median edge length.
        free_goal_dims: state dimensions a goal may leave free (NaN, or omitted when they are the last ones).
    """

    def __init__(
        self,
        graph: ExplicitGraph,
        *,
        snap_tolerance: float | None = None,
        free_goal_dims: tuple[int, ...] = (),
    ) -> None:
        self._graph = graph
        self._free = tuple(sorted(int(d) for d in free_goal_dims))
        states = graph.vertex_states
        self._kdtree = None if states is None else cKDTree(states)
        if snap_tolerance is None:
            median = float(np.median(graph.lengths)) if graph.num_edges else 0.0
            snap_tolerance = SNAP_FRACTION_OF_EDGE * median
        if not (np.isfinite(snap_tolerance) and snap_tolerance >= 0):
            raise QueryError(f"the snap tolerance must be finite and >= 0, got {snap_tolerance}")
        self.snap_tolerance = float(snap_tolerance)

    def resolve(self, value: Endpoint, label: str) -> int:
        """The vertex id of ``value`` (a vertex id, or a state within the snap tolerance of one).

        Raises:
            QueryError: not an id in range, not a finite state of the right length, or farther
                than the snap tolerance from every vertex.
        """
        resolved = self.snap(value, label)
        if isinstance(resolved, int):
            return resolved
        distance, vertex = self._kdtree.query(resolved)  # type: ignore[union-attr]
        raise QueryError(
            f"{label} state is {distance:.4g} from the nearest graph vertex ({int(vertex)}), farther "
            f"than the snap tolerance {self.snap_tolerance:.4g}: outside the graph's reach"
        )

    def snap(self, value: Endpoint, label: str) -> int | FloatArray:
        """A vertex id, or the validated (d,) state when it lies farther than the snap tolerance.

        Raises:
            QueryError: not an id in range, or not a finite state of the right length.
        """
        n = self._graph.num_vertices
        if isinstance(value, bool):
            raise QueryError(f"{label} must be a vertex id or a state, not a boolean")
        if isinstance(value, numbers.Integral):
            vertex = int(value)
            if not 0 <= vertex < n:
                raise QueryError(f"{label} vertex {vertex} outside the graph's vertices [0, {n})")
            return vertex
        try:
            state = np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise QueryError(f"{label} must be a vertex id or a state vector ({exc})") from None
        if state.ndim == 0:
            raise QueryError(f"{label} must be an integer vertex id or a state vector, got {value!r}")
        if self._kdtree is None:
            raise QueryError(f"this graph has no vertex states; give the {label} as a vertex id")
        dim = int(self._kdtree.m)
        free = self._free if label == "goal" else ()
        if free and state.shape == (dim - len(free),) and free == tuple(range(dim - len(free), dim)):
            state = np.concatenate([state, np.full(len(free), np.nan)])
        if state.shape != (dim,):
            also = f" (or {dim - len(free)} with the free ones left out)" if free else ""
            raise QueryError(f"{label} state must have {dim} values{also}, got shape {state.shape}")
        fixed = np.ones(dim, dtype=bool)
        fixed[list(free)] = False
        if not np.all(np.isfinite(state[fixed])) or np.any(np.isinf(state)):
            raise QueryError(f"{label} state has a NaN or infinite value: {state.tolist()}")
        if not np.all(np.isfinite(state)):
            return state  # a goal with free dimensions is joined by the connector
        distance, vertex = self._kdtree.query(state)
        if distance > self.snap_tolerance:
            return state
        return int(vertex)

    def nearest(self, state: FloatArray) -> tuple[float, int]:
        """(distance, vertex) of the vertex nearest to a validated state."""
        assert self._kdtree is not None
        distance, vertex = self._kdtree.query(state)
        return float(distance), int(vertex)
