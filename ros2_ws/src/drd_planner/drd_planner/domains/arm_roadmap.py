"""The arm's joint-space roadmap: statically valid configurations, k-nearest edges, interior edge samples.

Roadmap: scrambled Halton samples (``scipy.stats.qmc``, seeded) within the joint limits plus the
start and goal; only *statically valid* configurations are kept (no self-collision between the
checked sphere pairs, no moving sphere below the floor plane). Each vertex is joined to its k nearest
neighbours (Euclidean joint-space distance, ``cKDTree``); an edge is kept when every interpolated
configuration along it is statically valid as well, so self-collision never has to be tested again per
world. Only the connected component of the start is kept; the goal must be in it. Edge length (cost) =
joint-space Euclidean length in radians.

:class:`EdgeSamples` holds the interior samples of every edge at the check resolution (no joint moves
more than ``resolution`` radians between samples), each edge's in bisection order.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree
from scipy.stats import qmc

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.domains.arm_static import static_problems
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.ordering import bisection_order
from drd_planner.geometry.robot import RobotModel

__all__ = ["EdgeSamples", "build_roadmap", "graph_states", "segment_counts", "statically_valid"]


def statically_valid(robot: RobotModel, q: npt.ArrayLike, *, floor_z: float | None = 0.0) -> BoolArray:
    """(N,) True where an (N, D) configuration is within limits, self-collision-free and above the floor.

    Args:
        robot: the robot.
        q: configurations (rad).
        floor_z: no sphere of a moving link may reach below this height (m); None disables the test.
    """
    qa = robot.fk.as_configurations(q)
    ok = robot.within_limits(qa) & ~robot.self_collision(qa)
    if floor_z is not None:
        moving = robot.spheres.frame_index > 0
        centres = robot.sphere_centres(qa)[:, moving]
        ok &= np.all(centres[:, :, 2] - robot.spheres.radii[moving] >= floor_z, axis=1)
    return np.asarray(ok, dtype=bool)


def segment_counts(q_from: FloatArray, q_to: FloatArray, resolution: float) -> IntArray:
    """(E,) segments per straight joint-space edge so that no joint moves more than ``resolution`` (rad)."""
    steps = np.abs(q_to - q_from).max(axis=1) / resolution
    counts: IntArray = np.maximum(1, np.ceil(steps - 1e-9)).astype(np.int64)
    return counts


@dataclass(frozen=True)
class EdgeSamples:
    """Interior samples of every edge, each edge's in bisection order.

    Sample j of edge e is ``q_u + fractions[j] * (q_v - q_u)`` for ``offsets[e] <= j < offsets[e + 1]``.

    Attributes:
        offsets: (E + 1,) int64 start of each edge's samples.
        fractions: (T,) fractions in (0, 1) along the edge.
        edge_of: (T,) int64 edge of each sample.
    """

    offsets: IntArray
    fractions: FloatArray
    edge_of: IntArray

    @classmethod
    def of_graph(cls, graph: ExplicitGraph, resolution: float) -> EdgeSamples:
        """The samples of ``graph``'s edges at ``resolution`` radians (max joint step)."""
        if not (math.isfinite(resolution) and resolution > 0):
            raise ProblemError(f"edge check resolution must be finite and > 0 rad, got {resolution}")
        states = graph_states(graph)
        counts = segment_counts(states[graph.edges[:, 0]], states[graph.edges[:, 1]], resolution)
        interior = counts - 1
        offsets = np.concatenate([[0], np.cumsum(interior)]).astype(np.int64)
        fractions = np.empty(int(offsets[-1]))
        for e, n in enumerate(counts.tolist()):
            if n > 1:
                order = bisection_order(n - 1) + 1
                fractions[offsets[e] : offsets[e + 1]] = order / n
        edge_of = np.repeat(np.arange(graph.num_edges, dtype=np.int64), interior)
        return cls(offsets, fractions, edge_of)

    def configurations(self, graph: ExplicitGraph, edge: int) -> FloatArray:
        """(n_e - 1, D) interior configurations of one edge in bisection order."""
        states = graph_states(graph)
        u, v = graph.edges[edge]
        t = self.fractions[self.offsets[edge] : self.offsets[edge + 1]]
        out: FloatArray = states[u] + t[:, None] * (states[v] - states[u])
        return out


def graph_states(graph: ExplicitGraph) -> FloatArray:
    """The graph's (V, D) vertex states (radians) or ProblemError."""
    if graph.vertex_states is None:
        raise ProblemError("the arm domain needs a graph with (V, D) joint-space vertex states")
    return graph.vertex_states


def build_roadmap(
    robot: RobotModel,
    *,
    start: npt.ArrayLike,
    goal: npt.ArrayLike,
    num_samples: int,
    k: int,
    seed: int,
    resolution: float,
    floor_z: float | None = 0.0,
) -> ExplicitGraph:
    """A statically valid k-nearest-neighbour roadmap; vertex 0 is ``start``, vertex 1 ``goal``.

    Args:
        robot: the robot (limits, spheres, self-collision pairs).
        start: (D,) start configuration (rad).
        goal: (D,) goal configuration (rad).
        num_samples: Halton samples drawn (before dropping invalid ones).
        k: neighbours per vertex (edges are the symmetric union).
        seed: Halton scrambling seed.
        resolution: max joint step (rad) when validating edges.
        floor_z: floor height (m) for the static test (None: no floor).

    Returns:
        An undirected graph with edges ``[u, v]``, u < v, sorted; ``vertex_states`` (V, D).

    Raises:
        ProblemError: bad arguments, start or goal not statically valid, or start and goal disconnected.
    """
    if num_samples < 1 or k < 1:
        raise ProblemError(f"roadmap needs num_samples >= 1 and k >= 1, got {num_samples}, {k}")
    ends = robot.fk.as_configurations(np.stack([np.asarray(start, float), np.asarray(goal, float)]))
    valid_ends = statically_valid(robot, ends, floor_z=floor_z)
    for name, end, ok in zip(("start", "goal"), ends, valid_ends.tolist(), strict=True):
        if not ok:
            why = "; ".join(static_problems(robot, end, floor_z=floor_z, name=name))
            raise ProblemError(f"{name} configuration is not statically valid: {why}")
    unit = qmc.Halton(d=robot.dof, scramble=True, seed=seed).random(num_samples)
    samples = robot.lower + unit * (robot.upper - robot.lower)
    samples = samples[statically_valid(robot, samples, floor_z=floor_z)]
    states = np.concatenate([ends, samples])
    count = states.shape[0]
    kk = min(k + 1, count)
    _, neighbours = cKDTree(states).query(states, kk)
    pairs = np.stack([np.repeat(np.arange(count), kk - 1), neighbours[:, 1:].ravel()], axis=1)
    pairs = np.unique(np.sort(pairs, axis=1), axis=0).astype(np.int64)
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]
    lengths = np.linalg.norm(states[pairs[:, 1]] - states[pairs[:, 0]], axis=1)
    candidate = ExplicitGraph(pairs, lengths, count, directed=False, vertex_states=states)
    samples_of = EdgeSamples.of_graph(candidate, resolution)
    interior = states[pairs[samples_of.edge_of, 0]] + samples_of.fractions[:, None] * (
        states[pairs[samples_of.edge_of, 1]] - states[pairs[samples_of.edge_of, 0]]
    )
    bad_sample = ~statically_valid(robot, interior, floor_z=floor_z)
    keep = np.bincount(samples_of.edge_of[bad_sample], minlength=pairs.shape[0]) == 0
    pairs, lengths = pairs[keep], lengths[keep]
    adjacency = coo_array((np.ones(pairs.shape[0]), (pairs[:, 0], pairs[:, 1])), shape=(count, count))
    _, labels = connected_components(adjacency, directed=False)
    if labels[0] != labels[1]:
        raise ProblemError(
            f"start and goal are not connected in the roadmap (num_samples={num_samples}, k={k}, "
            f"seed={seed}); raise num_samples or k"
        )
    component = np.nonzero(labels == labels[0])[0]
    renumber = np.full(count, -1, dtype=np.int64)
    renumber[component] = np.arange(component.shape[0])
    in_component = labels[pairs[:, 0]] == labels[0]
    new_pairs = renumber[pairs[in_component]]
    return ExplicitGraph(
        new_pairs,
        lengths[in_component],
        int(component.shape[0]),
        directed=False,
        vertex_states=states[component],
    )
