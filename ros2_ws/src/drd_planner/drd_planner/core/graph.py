"""Explicit graphs whose edges are the expensive tests."""

from __future__ import annotations

import itertools
from dataclasses import dataclass

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
                raise ProblemError(f"vertex states must have shape ({self.num_vertices}, d), got {states.shape}")
            object.__setattr__(self, "vertex_states", states)
        object.__setattr__(self, "edges", edges)
        object.__setattr__(self, "lengths", lengths)
        if edges.shape[0] > 1:  # duplicates found at once (vectorised); the lookup is built on first use
            pairs = edges if self.directed else np.sort(edges, axis=1)
            keys = pairs[:, 0] * max(self.num_vertices, 1) + pairs[:, 1]
            order = np.argsort(keys, kind="stable")
            repeated = np.flatnonzero(keys[order][1:] == keys[order][:-1])
            if repeated.size:
                u, v = (int(x) for x in edges[order[repeated[0] + 1]])
                raise ProblemError(f"duplicate edge ({u}, {v}) in graph")

    @property
    def _lookup(self) -> dict[tuple[int, int], int]:
        """(u, v) -> edge id (both orientations of an undirected edge), built on first use."""
        cached: dict[tuple[int, int], int] | None = self.__dict__.get("_lookup_cache")
        if cached is None:
            cached = {}
            for eid, (u, v) in enumerate(self.edges.tolist()):
                cached[(u, v)] = eid
                if not self.directed:
                    cached[(v, u)] = eid
            object.__setattr__(self, "_lookup_cache", cached)
        return cached

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
