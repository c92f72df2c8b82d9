"""Explicit graphs whose edges are the expensive tests."""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.exceptions import ProblemError


@dataclass(frozen=True)
class ExplicitGraph:
    """A graph with one test (collision check) per edge.

    Attributes:
        edges: (E, 2) int64 vertex ids (0-based) ``[u, v]``. For undirected graphs each physical edge
            appears once; its orientation is arbitrary.
        lengths: (E,) float64 edge lengths in the domain's length unit (metres, radians, ...).
        directed: whether edges may only be traversed from ``u`` to ``v``.
        vertex_states: (V, d) float64 vertex states (x, y, ... or joint angles), or None when unknown.
        num_vertices: V.
    """

    edges: IntArray
    lengths: FloatArray
    num_vertices: int
    directed: bool = False
    vertex_states: FloatArray | None = None
    _lookup: dict[tuple[int, int], int] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        edges = np.asarray(self.edges, dtype=np.int64)
        lengths = np.asarray(self.lengths, dtype=np.float64)
        if edges.ndim != 2 or edges.shape[1] != 2:
            raise ProblemError(f"graph edges must have shape (E, 2), got {edges.shape}")
        if lengths.shape != (edges.shape[0],):
            raise ProblemError(f"graph lengths must have shape ({edges.shape[0]},), got {lengths.shape}")
        if edges.size and (edges.min() < 0 or edges.max() >= self.num_vertices):
            raise ProblemError(f"graph edge endpoints must lie in [0, {self.num_vertices})")
        if not np.all(np.isfinite(lengths)) or np.any(lengths < 0):
            raise ProblemError("graph edge lengths must be finite and non-negative")
        if self.vertex_states is not None:
            states = np.asarray(self.vertex_states, dtype=np.float64)
            if states.ndim != 2 or states.shape[0] != self.num_vertices:
                raise ProblemError(
                    f"vertex states must have shape ({self.num_vertices}, d), got {states.shape}"
                )
            object.__setattr__(self, "vertex_states", states)
        object.__setattr__(self, "edges", edges)
        object.__setattr__(self, "lengths", lengths)
        lookup: dict[tuple[int, int], int] = {}
        for eid, (u, v) in enumerate(edges.tolist()):
            if (u, v) in lookup or (not self.directed and (v, u) in lookup):
                raise ProblemError(f"duplicate edge ({u}, {v}) in graph")
            lookup[(u, v)] = eid
            if not self.directed:
                lookup[(v, u)] = eid
        object.__setattr__(self, "_lookup", lookup)

    @property
    def num_edges(self) -> int:
        """E, the number of tests."""
        return int(self.edges.shape[0])

    def edge_id(self, u: int, v: int) -> int:
        """The id of the edge from ``u`` to ``v`` (either orientation when undirected)."""
        try:
            return self._lookup[(int(u), int(v))]
        except KeyError:
            raise ProblemError(f"no edge from vertex {u} to vertex {v}") from None

    def vertex_path_to_edges(self, vertices: npt.ArrayLike) -> IntArray:
        """Edge ids (L,) along a vertex sequence (L + 1,)."""
        seq = np.asarray(vertices, dtype=np.int64).ravel()
        return np.array([self.edge_id(a, b) for a, b in itertools.pairwise(seq.tolist())], dtype=np.int64)
