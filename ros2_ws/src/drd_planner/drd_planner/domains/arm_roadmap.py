"""The arm's joint-space roadmap: statically valid configurations, k-nearest edges, interior edge samples.

Roadmap: the *anchors* (vertex 0 the start, 1 the goal, 2 + i the spec's ``extra_states[i]``, e.g. the
start and goal states of a scene set's MoveIt requests) plus scrambled Halton samples (``scipy.stats.qmc``,
seeded) within the joint limits; only *statically valid* configurations are kept (within the joint limits,
no self-collision between the checked sphere pairs, no moving sphere below the floor plane), and an anchor
that is not is refused with the failing check and the parameter that changes it. Each vertex is joined to
its k nearest neighbours (Euclidean joint-space distance, ``cKDTree``); an edge is kept when every
interpolated configuration along it is statically valid as well, so self-collision never has to be tested
again per world. Only the connected component of the start is kept; every anchor must be in it. Edge
length (cost) = joint-space Euclidean length in radians.

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
from drd_planner.domains.arm_params import ArmParams
from drd_planner.domains.arm_static import WHERE, floor_accepting, lowest_bottoms, static_problems
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.ordering import bisection_order
from drd_planner.geometry.robot import RobotModel

__all__ = [
    "DUPLICATE_TOLERANCE",
    "EdgeSamples",
    "anchor_names",
    "anchor_states",
    "build_roadmap",
    "graph_states",
    "segment_counts",
    "statically_valid",
]


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


def build_roadmap(robot: RobotModel, params: ArmParams) -> ExplicitGraph:
    """A statically valid k-nearest-neighbour roadmap of ``params`` (:class:`ArmParams`).

    Vertex 0 is ``params.start``, vertex 1 ``params.goal`` and vertex ``2 + i`` is
    ``params.extra_states[i]`` (the *anchors*); the Halton samples that are statically valid follow, then
    every vertex is joined to its ``params.k`` nearest neighbours. Only the connected component of the
    start is kept, and every anchor must be in it, so the anchors keep their ids. With no extra states the
    roadmap is the same, byte for byte, as before extra states existed.

    Args:
        robot: the robot (limits, spheres, self-collision pairs).
        params: start, goal, extra_states (rad), num_samples, k, seed (Halton scrambling), resolution (rad,
            max joint step when validating edges) and floor_z (m; None: no floor); the robot files of
            ``params`` are not read here.

    Returns:
        An undirected graph with edges ``[u, v]``, u < v, sorted; ``vertex_states`` (V, D).

    Raises:
        ProblemError: bad sizes; an anchor with the wrong number of joint values, not statically valid
            (the failing check and the parameter that changes it named) or repeated; an anchor not
            connected to the start (the num_samples and k to try named).
    """
    if params.num_samples < 1 or params.k < 1:
        raise ProblemError(
            f"roadmap needs num_samples >= 1 and k >= 1, got {params.num_samples}, {params.k}: change them {WHERE}"
        )
    anchors = anchor_states(robot, params)
    unit = qmc.Halton(d=robot.dof, scramble=True, seed=params.seed).random(params.num_samples)
    samples = robot.lower + unit * (robot.upper - robot.lower)
    samples = samples[statically_valid(robot, samples, floor_z=params.floor_z)]
    states = np.concatenate([anchors, samples])
    pairs, lengths = _valid_edges(robot, states, params)
    return _start_component(states, pairs, lengths, anchors.shape[0], params)


def anchor_names(num_extra: int) -> list[str]:
    """The spec names of the anchors: ``start``, ``goal``, ``extra_states[0]`` ... ``extra_states[M-1]``."""
    return ["start", "goal", *(f"extra_states[{i}]" for i in range(num_extra))]


def anchor_states(robot: RobotModel, params: ArmParams) -> FloatArray:
    """(2 + M, D) start, goal and extra states (rad), each checked for size, static validity and repeats.

    Raises:
        ProblemError: the first anchor with the wrong number of joint values; the first one that is not
            statically valid (which check, which parameter; the other invalid ones listed); the first extra
            state within :data:`DUPLICATE_TOLERANCE` of the start, the goal or an earlier extra state.
    """
    rows = [params.start, params.goal, *params.extra_states]
    names = anchor_names(len(params.extra_states))
    for name, row in zip(names, rows, strict=True):
        if len(row) != robot.dof:
            raise ProblemError(
                f"{name} has {len(row)} joint values; the arm needs {robot.dof} joint values "
                f"({', '.join(robot.chain.joint_names)}): change {name} {WHERE}"
            )
    anchors = np.array(rows, dtype=np.float64).reshape(len(rows), robot.dof)
    invalid = np.flatnonzero(~statically_valid(robot, anchors, floor_z=params.floor_z)).tolist()
    if invalid:
        first = invalid[0]
        why = "; ".join(static_problems(robot, anchors[first], floor_z=params.floor_z, name=names[first]))
        bottoms = lowest_bottoms(robot, anchors)
        if params.floor_z is not None and np.count_nonzero(bottoms < params.floor_z) > 1:
            why += (
                f"; floor_z = {floor_accepting(float(bottoms.min())):g} passes the floor test of all "
                f"{np.count_nonzero(bottoms < params.floor_z)} states below the floor"
            )
        also = f" (also not statically valid: {_listed([names[i] for i in invalid[1:]])})" if invalid[1:] else ""
        raise ProblemError(f"{names[first]} configuration is not statically valid: {why}{also}")
    _refuse_repeats(anchors, names)
    return anchors


#: Two anchors whose joint values all differ by at most this (rad) are the same configuration (refused).
DUPLICATE_TOLERANCE = 1e-9


def _refuse_repeats(anchors: FloatArray, names: list[str]) -> None:
    """ProblemError for the first extra state (index >= 2) that repeats an earlier anchor."""
    close = cKDTree(anchors).query_pairs(DUPLICATE_TOLERANCE, p=np.inf, output_type="ndarray")
    close = np.sort(close, axis=1)
    close = close[close[:, 1] >= 2]
    if close.shape[0]:
        later = int(close[:, 1].min())
        earlier = int(close[close[:, 1] == later, 0].min())
        raise ProblemError(
            f"{names[later]} repeats {names[earlier]} (every joint within {DUPLICATE_TOLERANCE:g} rad): give "
            "each extra state once and none equal to start or goal (vertex 2 + i is extra_states[i]), e.g. "
            "numpy.unique(states, axis=0)"
        )


def _listed(names: list[str], most: int = 10) -> str:
    """``a, b, c`` with at most ``most`` names, then how many more."""
    shown = ", ".join(names[:most])
    return shown if len(names) <= most else f"{shown} and {len(names) - most} more"


def _valid_edges(robot: RobotModel, states: FloatArray, params: ArmParams) -> tuple[IntArray, FloatArray]:
    """(E, 2) k-nearest pairs u < v, sorted, whose every interior sample is statically valid; (E,) lengths."""
    count = states.shape[0]
    kk = min(params.k + 1, count)
    _, neighbours = cKDTree(states).query(states, kk)
    pairs = np.stack([np.repeat(np.arange(count), kk - 1), neighbours[:, 1:].ravel()], axis=1)
    pairs = np.unique(np.sort(pairs, axis=1), axis=0).astype(np.int64)
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]
    lengths = np.linalg.norm(states[pairs[:, 1]] - states[pairs[:, 0]], axis=1)
    candidate = ExplicitGraph(pairs, lengths, count, directed=False, vertex_states=states)
    samples_of = EdgeSamples.of_graph(candidate, params.resolution)
    interior = states[pairs[samples_of.edge_of, 0]] + samples_of.fractions[:, None] * (
        states[pairs[samples_of.edge_of, 1]] - states[pairs[samples_of.edge_of, 0]]
    )
    bad_sample = ~statically_valid(robot, interior, floor_z=params.floor_z)
    keep = np.bincount(samples_of.edge_of[bad_sample], minlength=pairs.shape[0]) == 0
    return pairs[keep], lengths[keep]


def _start_component(
    states: FloatArray, pairs: IntArray, lengths: FloatArray, num_anchors: int, params: ArmParams
) -> ExplicitGraph:
    """The graph of the start's connected component (vertices keep their order); every anchor must be in it."""
    count = states.shape[0]
    adjacency = coo_array((np.ones(pairs.shape[0]), (pairs[:, 0], pairs[:, 1])), shape=(count, count))
    _, labels = connected_components(adjacency, directed=False)
    apart = np.flatnonzero(labels[:num_anchors] != labels[0]).tolist()
    if apart:
        component_size = int(np.count_nonzero(labels == labels[0]))
        names = anchor_names(num_anchors - 2)
        verb = "is" if len(apart) == 1 else "are"
        what = (
            "start and goal are not connected"
            if apart[0] == 1
            else f"{_listed([names[i] for i in apart])} {verb} not connected to the start"
        )
        raise ProblemError(
            f"{what} in the roadmap (num_samples={params.num_samples}, k={params.k}, seed={params.seed}; "
            f"the start's component has {component_size} of {count} vertices): raise num_samples "
            f"(e.g. to {2 * params.num_samples}) or k (e.g. to {params.k + 4}) {WHERE}"
        )
    component = np.nonzero(labels == labels[0])[0]
    renumber = np.full(count, -1, dtype=np.int64)
    renumber[component] = np.arange(component.shape[0])
    in_component = labels[pairs[:, 0]] == labels[0]
    return ExplicitGraph(
        renumber[pairs[in_component]],
        lengths[in_component],
        int(component.shape[0]),
        directed=False,
        vertex_states=states[component],
    )
