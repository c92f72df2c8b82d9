"""The 7-DoF arm domain: a joint-space roadmap of the Franka Panda and sphere-model edge checks.

Roadmap: scrambled Halton samples (``scipy.stats.qmc``, seeded) within the joint limits plus the
start and goal; only *statically valid* configurations are kept (no self-collision between the
checked sphere pairs, no moving sphere below the floor plane). Each vertex is joined to its k nearest
neighbours (Euclidean joint-space distance, ``cKDTree``); an edge is kept when every interpolated
configuration along it is statically valid as well, so self-collision never has to be tested again per
world. Only the connected component of the start is kept; the goal must be in it. Edge length (cost) =
joint-space Euclidean length in radians.

Edge check: the straight joint-space segment is sampled so that no joint moves more than
``resolution`` radians between samples; the end vertices are checked first (cached per world), then
the interior samples in bisection order, stopping at the first sphere that meets an obstacle (the
scene's margin included). Forward kinematics is batched over all samples of an edge, and in
:meth:`ArmEdgeChecker.check_many` over all samples of many edges at once. Each sample is tested in two
levels through the scene API: one bounding sphere per link first, then the spheres of the links whose
bounding sphere touches something.

Defaults (Panda; 600 Halton samples, k = 8, resolution 0.05 rad): 489 vertices and 2475 edges, about
31 interior samples per edge. Start and goal (:data:`DEFAULT_START`, :data:`DEFAULT_GOAL`) hold the
gripper low over the front left and front right of the table, so objects on the table often block the
direct start-goal edge (1.6 rad, the shortest path) and the arm must lift over or reach around them.

The robot model is read from the shared Panda files (``$DRD_SHARED_DATA/panda`` or
``../shared/data/panda`` next to the repository) unless the spec names other files.
"""

from __future__ import annotations

import functools
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree
from scipy.stats import qmc

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.domains.arm_description import check_description_size, check_robot_coordinates
from drd_planner.domains.arm_static import static_problems
from drd_planner.domains.arm_worlds import (
    WORLD_MODELS,
    ArmWorld,
    KeepClear,
    sample_arm_world,
    world_from_planning_scene,
)
from drd_planner.exceptions import GeometryError, ProblemError
from drd_planner.geometry.ordering import bisection_order
from drd_planner.geometry.robot import RobotModel
from drd_planner.geometry.scene import Scene
from drd_planner.planning.map_limits import MapLimits

#: Default start: the gripper low (about 0.13 m above the base) over the front left of the table (rad).
DEFAULT_START: tuple[float, ...] = (0.5, 0.7, 0.0, -1.6, 0.0, 2.4, 0.785)
#: Default goal: the mirror image, low over the front right of the table (rad).
DEFAULT_GOAL: tuple[float, ...] = (-0.5, 0.7, 0.0, -1.6, 0.0, 2.4, 0.785)
#: Clearance (m) added to the robot's spheres at start and goal when placing random obstacles.
KEEP_CLEAR_CLEARANCE = 0.02
#: Interpolated configurations per forward-kinematics block in :meth:`ArmEdgeChecker.check_many`.
CHECK_BLOCK = 4096

#: Keys of :meth:`ArmDomain.spec` (the constructor's keyword arguments).
SPEC_KEYS: tuple[str, ...] = (
    "urdf_path",
    "sphere_urdf_path",
    "srdf_path",
    "start",
    "goal",
    "num_samples",
    "k",
    "seed",
    "resolution",
    "margin",
    "floor_z",
)

__all__ = [
    "DEFAULT_GOAL",
    "DEFAULT_START",
    "SPEC_KEYS",
    "ArmDomain",
    "ArmEdgeChecker",
    "EdgeSamples",
    "build_roadmap",
    "check_arm_edge",
    "default_panda_dir",
    "load_robot",
    "robot_texts",
    "statically_valid",
]


# --------------------------------------------------------------------------------------------------
# Robot files


def default_panda_dir() -> Path:
    """The shared Panda folder: ``$DRD_SHARED_DATA/panda``, else ``<repo>/../shared/data/panda``.

    Raises:
        ProblemError: the folder does not exist.
    """
    env = os.environ.get("DRD_SHARED_DATA")
    base = Path(env) if env else Path(__file__).resolve().parents[5].parent / "shared" / "data"
    folder = base / "panda"
    if not folder.is_dir():
        raise ProblemError(
            f"Panda model folder {folder} not found; set DRD_SHARED_DATA or give urdf_path in the arm spec"
        )
    return folder


@functools.lru_cache(maxsize=8)
def _robot_from_text(urdf: str, sphere_urdf: str | None, srdf: str | None) -> RobotModel:
    """A cached :class:`RobotModel` (parsing takes tens of milliseconds)."""
    return RobotModel.from_urdf(urdf, sphere_urdf=sphere_urdf, srdf=srdf)


def robot_texts(
    urdf_path: str | None = None, sphere_urdf_path: str | None = None, srdf_path: str | None = None
) -> tuple[str, str | None, str | None]:
    """(URDF, spherized URDF or None, SRDF or None) texts of robot files; None means the shared Panda.

    With every path None: ``panda.urdf`` (kinematics), ``panda_spherized.urdf`` (spheres) and
    ``panda.srdf``. With ``urdf_path`` given, the other two default to "none" (the URDF must then be
    spherized itself and adjacent links are excluded from self-collision).

    Raises:
        ProblemError: a file cannot be read, or the shared Panda folder is missing.
    """
    if urdf_path is None:
        folder = default_panda_dir()
        urdf_path = str(folder / "panda.urdf")
        sphere_urdf_path = sphere_urdf_path or str(folder / "panda_spherized.urdf")
        srdf_path = srdf_path or str(folder / "panda.srdf")

    def read(path: str | None) -> str | None:
        if path is None:
            return None
        try:
            return Path(path).read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise ProblemError(f"cannot read robot description {path}: {exc}") from exc

    urdf = read(urdf_path)
    assert urdf is not None
    return urdf, read(sphere_urdf_path), read(srdf_path)


def load_robot(
    urdf_path: str | None = None, sphere_urdf_path: str | None = None, srdf_path: str | None = None
) -> RobotModel:
    """The robot model from files (see :func:`robot_texts`; None means the shared Panda files).

    Raises:
        ProblemError: a file cannot be read.
        GeometryError: a description is invalid.
    """
    return _robot_from_text(*robot_texts(urdf_path, sphere_urdf_path, srdf_path))


# --------------------------------------------------------------------------------------------------
# Roadmap


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
        states = _states(graph)
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
        states = _states(graph)
        u, v = graph.edges[edge]
        t = self.fractions[self.offsets[edge] : self.offsets[edge + 1]]
        out: FloatArray = states[u] + t[:, None] * (states[v] - states[u])
        return out


def _states(graph: ExplicitGraph) -> FloatArray:
    """The graph's (V, D) vertex states or ProblemError."""
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


# --------------------------------------------------------------------------------------------------
# Edge checking


class ArmEdgeChecker:
    """Checks the edges of a joint-space graph against one collision scene.

    Answers are cached: asking for an edge twice costs nothing the second time.

    Args:
        robot: the robot (FK and spheres).
        graph: the roadmap; ``vertex_states`` (V, D) in radians.
        scene: obstacles; its margin inflates every robot sphere.
        resolution: max joint step between samples (rad); ignored when ``samples`` is given.
        samples: precomputed :class:`EdgeSamples` of ``graph`` (shared between checkers of one domain).
        self_collision: also test self-collision of every sample (needed only for graphs not built by
            :func:`build_roadmap`, which already excludes self-colliding edges).
    """

    def __init__(
        self,
        *,
        robot: RobotModel,
        graph: ExplicitGraph,
        scene: Scene,
        resolution: float = 0.05,
        samples: EdgeSamples | None = None,
        self_collision: bool = False,
    ) -> None:
        states = _states(graph)
        if states.shape[1] != robot.dof:
            raise ProblemError(f"graph states have {states.shape[1]} joints, the robot {robot.dof}")
        self.robot = robot
        self.graph = graph
        self.scene = scene
        self.samples = samples if samples is not None else EdgeSamples.of_graph(graph, resolution)
        self.self_collision = self_collision
        self._states = states
        self._fixed = np.nonzero(robot.spheres.frame_index == 0)[0]
        self._moving_groups = np.nonzero(robot.groups.frame_index > 0)[0]
        self._group_radii = robot.groups.radii[self._moving_groups]
        self._edge_state = np.zeros(graph.num_edges, dtype=np.int8)  # 0 unknown, 1 free, -1 blocked
        self._vertex_state = np.zeros(graph.num_vertices, dtype=np.int8)
        self._base_free: bool | None = None
        self.configurations_checked = 0

    # ----------------------------------------------------------------------------------------------

    def _edge_ids(self, edges: npt.ArrayLike) -> IntArray:
        """Validated (K,) edge ids."""
        ids = np.asarray(edges, dtype=np.int64).reshape(-1)
        if ids.size and (ids.min() < 0 or ids.max() >= self.graph.num_edges):
            raise ProblemError(f"edge ids must lie in [0, {self.graph.num_edges})")
        return ids

    def _base_is_free(self) -> bool:
        """Whether the spheres fixed to the root link (the same in every configuration) are free."""
        if self._base_free is None:
            if self._fixed.size == 0:
                self._base_free = True
            else:
                centres = self.robot.sphere_centres(self._states[:1])[0, self._fixed]
                self._base_free = not self.scene.spheres_collide(
                    centres, self.robot.spheres.radii[self._fixed]
                )
        return self._base_free

    def _candidates(self, q: FloatArray) -> tuple[IntArray, IntArray, FloatArray]:
        """Spheres of (N, D) ``q`` whose link's bounding sphere touches the scene (first hierarchy level).

        Returns:
            ``(config, sphere, centres)``: for each of the C candidate spheres its configuration (row of
            ``q``), sphere index and (C, 3) centre (m), ordered by configuration.
        """
        self.configurations_checked += q.shape[0]
        frames = self.robot.fk.frames(q)
        groups = self.robot.group_centres_from_frames(frames)[:, self._moving_groups]
        radii = np.broadcast_to(self._group_radii, groups.shape[:2]).reshape(-1)
        near = self.scene.spheres_collide_mask(groups.reshape(-1, 3), radii).reshape(groups.shape[:2])
        rows, which = np.nonzero(near)
        if rows.size == 0:
            empty = np.zeros(0, dtype=np.int64)
            return empty, empty, np.zeros((0, 3))
        position, sphere = self.robot.groups.expand(self._moving_groups[which])
        config = rows[position]
        configs, row_of = np.unique(config, return_inverse=True)
        centres = self.robot.sphere_centres_from_frames(frames[configs])[row_of, sphere]
        return config, sphere, centres

    def _blocked_configs(self, q: FloatArray) -> BoolArray:
        """(N,) True where a configuration's moving spheres hit the scene (or it self-collides)."""
        config, sphere, centres = self._candidates(q)
        blocked = np.zeros(q.shape[0], dtype=bool)
        if config.size:
            hits = self.scene.spheres_collide_mask(centres, self.robot.spheres.radii[sphere])
            blocked[config[hits]] = True
        if self.self_collision:
            blocked |= self.robot.self_collision(q)
        return blocked

    def _vertices_free(self, vertices: IntArray) -> BoolArray:
        """(K,) whether each vertex configuration is free (cached)."""
        unknown = np.unique(vertices[self._vertex_state[vertices] == 0])
        if unknown.size:
            blocked = self._blocked_configs(self._states[unknown])
            self._vertex_state[unknown] = np.where(blocked, -1, 1)
        out: BoolArray = self._vertex_state[vertices] > 0
        return out

    def _interior_free(self, edge: int) -> bool:
        """Whether the interior samples of one edge are free, in bisection order with early exit."""
        q = self.samples.configurations(self.graph, edge)
        if q.shape[0] == 0:
            return True
        if self.self_collision and bool(self.robot.self_collision(q).any()):
            return False
        _, sphere, centres = self._candidates(q)
        return not (sphere.size and self.scene.spheres_collide(centres, self.robot.spheres.radii[sphere]))

    # ----------------------------------------------------------------------------------------------

    def check_motion(self, states: npt.ArrayLike) -> bool:
        """True when a joint-space motion off the roadmap ((K, D) configurations, radians) is free.

        The samples must be as dense as the roadmap's check resolution (the planner's connector uses it).
        """
        q = np.asarray(states, dtype=np.float64)
        if q.ndim != 2 or q.shape[0] < 1 or q.shape[1] != self._states.shape[1] or not np.all(np.isfinite(q)):
            raise ProblemError(f"a motion must be a finite (K, {self._states.shape[1]}) array, got {q.shape}")
        return self._base_is_free() and not bool(self._blocked_configs(q).any())

    def check(self, edge: int) -> bool:
        """True when ``edge`` is free: end vertices first, then interior samples in bisection order."""
        e = int(self._edge_ids([edge])[0])
        if self._edge_state[e] == 0:
            u, v = self.graph.edges[e]
            free = (
                self._base_is_free()
                and bool(self._vertices_free(np.array([u, v])).all())
                and self._interior_free(e)
            )
            self._edge_state[e] = 1 if free else -1
        return bool(self._edge_state[e] > 0)

    def check_many(self, edges: npt.ArrayLike) -> BoolArray:
        """(K,) bool free flags of (K,) edge ids; the same answers as :meth:`check`, FK batched over edges."""
        ids = self._edge_ids(edges)
        todo = np.unique(ids[self._edge_state[ids] == 0])
        if todo.size:
            if not self._base_is_free():
                self._edge_state[todo] = -1
            else:
                ends = self.graph.edges[todo]
                ends_free = self._vertices_free(ends.reshape(-1)).reshape(-1, 2).all(axis=1)
                self._edge_state[todo[~ends_free]] = -1
                self._check_interiors(todo[ends_free])
        out: BoolArray = self._edge_state[ids] > 0
        return out

    def _check_interiors(self, edges: IntArray) -> None:
        """Decide edges whose end vertices are free, FK batched over blocks of samples of many edges."""
        offsets = self.samples.offsets
        counts = offsets[edges + 1] - offsets[edges]
        start = 0
        while start < edges.shape[0]:
            stop = start + 1
            total = int(counts[start])
            while stop < edges.shape[0] and total + int(counts[stop]) <= CHECK_BLOCK:
                total += int(counts[stop])
                stop += 1
            block = edges[start:stop]
            sample_ids = np.concatenate([np.arange(offsets[e], offsets[e + 1]) for e in block.tolist()])
            owner = np.repeat(np.arange(block.shape[0]), counts[start:stop])
            u = self._states[self.graph.edges[block[owner], 0]]
            v = self._states[self.graph.edges[block[owner], 1]]
            q = u + self.samples.fractions[sample_ids][:, None] * (v - u)
            blocked = self._blocked_configs(q) if q.shape[0] else np.zeros(0, dtype=bool)
            hits = np.bincount(owner[blocked], minlength=block.shape[0])
            self._edge_state[block] = np.where(hits > 0, -1, 1)
            start = stop


def check_arm_edge(
    *,
    urdf: str,
    scene: Scene,
    graph: ExplicitGraph,
    edge: int,
    resolution: float = 0.05,
    sphere_urdf: str | None = None,
    srdf: str | None = None,
) -> bool:
    """Whether one roadmap edge is free for the robot of a URDF string in ``scene`` (node-facing).

    Self-collision of every sample is tested as well (the graph may come from anywhere). The robot model
    is cached per description text, so repeated calls only pay for the check.

    Args:
        urdf: URDF text (``robot_description``).
        scene: obstacles (its margin applies).
        graph: joint-space roadmap with (V, D) ``vertex_states`` in radians.
        edge: the edge id.
        resolution: max joint step between samples (rad).
        sphere_urdf: spherized URDF text when ``urdf`` has mesh collisions.
        srdf: SRDF text (self-collision exclusions).

    Raises:
        GeometryError: invalid descriptions.
        ProblemError: bad edge id or graph.
    """
    robot = _robot_from_text(urdf, sphere_urdf, srdf)
    edge_graph = ExplicitGraph(
        graph.edges[[edge]] if 0 <= edge < graph.num_edges else graph.edges[:0],
        graph.lengths[[edge]] if 0 <= edge < graph.num_edges else graph.lengths[:0],
        graph.num_vertices,
        vertex_states=graph.vertex_states,
    )
    if edge_graph.num_edges != 1:
        raise ProblemError(f"edge id {edge} is not in [0, {graph.num_edges})")
    checker = ArmEdgeChecker(
        robot=robot, graph=edge_graph, scene=scene, resolution=resolution, self_collision=True
    )
    return checker.check(0)


# --------------------------------------------------------------------------------------------------
# Domain


class ArmDomain:
    """The arm domain (registry name ``"arm"``): Panda roadmap, world models and sphere edge checks.

    Args:
        urdf_path: kinematic URDF file; None: the shared Panda (``panda.urdf`` + ``panda_spherized.urdf``
            spheres + ``panda.srdf``), see :func:`load_robot`.
        sphere_urdf_path: spherized URDF file (spheres; the kinematic URDF itself when None).
        srdf_path: SRDF file (self-collision exclusions; adjacent links when None).
        start: (D,) start configuration (rad).
        goal: (D,) goal configuration (rad).
        num_samples: Halton samples drawn for the roadmap.
        k: nearest neighbours per vertex.
        seed: Halton scrambling seed.
        resolution: max joint step between edge samples (rad).
        margin: safety distance added to every robot sphere in world checks (m).
        floor_z: no moving sphere below this height in the roadmap (m); None disables the floor.

    Raises:
        ProblemError: invalid values, unreadable or invalid robot files, or start and goal not connected.
    """

    name = "arm"

    def __init__(
        self,
        *,
        urdf_path: str | None = None,
        sphere_urdf_path: str | None = None,
        srdf_path: str | None = None,
        start: Sequence[float] = DEFAULT_START,
        goal: Sequence[float] = DEFAULT_GOAL,
        num_samples: int = 600,
        k: int = 8,
        seed: int = 0,
        resolution: float = 0.05,
        margin: float = 0.0,
        floor_z: float | None = 0.0,
    ) -> None:
        try:
            self._spec = _normalise_spec(
                {
                    "urdf_path": urdf_path,
                    "sphere_urdf_path": sphere_urdf_path,
                    "srdf_path": srdf_path,
                    "start": start,
                    "goal": goal,
                    "num_samples": num_samples,
                    "k": k,
                    "seed": seed,
                    "resolution": resolution,
                    "margin": margin,
                    "floor_z": floor_z,
                }
            )
        except (TypeError, ValueError) as exc:
            raise ProblemError(f"invalid arm spec: {exc}") from exc
        s = self._spec
        try:
            self._robot_texts = robot_texts(s["urdf_path"], s["sphere_urdf_path"], s["srdf_path"])
            self.robot = _robot_from_text(*self._robot_texts)
        except GeometryError as exc:
            raise ProblemError(f"arm robot model: {exc}") from exc
        if len(s["start"]) != self.robot.dof or len(s["goal"]) != self.robot.dof:
            raise ProblemError(f"start and goal need {self.robot.dof} joint values")
        self.resolution: float = s["resolution"]
        self.margin: float = s["margin"]
        self._graph = build_roadmap(
            self.robot,
            start=s["start"],
            goal=s["goal"],
            num_samples=s["num_samples"],
            k=s["k"],
            seed=s["seed"],
            resolution=self.resolution,
            floor_z=s["floor_z"],
        )
        self.samples = EdgeSamples.of_graph(self._graph, self.resolution)
        ends = np.array([s["start"], s["goal"]], dtype=np.float64)
        centres = self.robot.sphere_centres(ends).reshape(-1, 3)
        radii = np.tile(self.robot.spheres.radii, 2) + self.margin + KEEP_CLEAR_CLEARANCE
        self.keep_clear = KeepClear(centres, radii)

    @classmethod
    def from_spec(cls, spec: Mapping[str, Any]) -> ArmDomain:
        """The domain of a spec (keys are the constructor's arguments; missing keys take the defaults).

        Raises:
            ProblemError: unknown keys or invalid values.
        """
        unknown = sorted(set(spec) - set(SPEC_KEYS))
        if unknown:
            raise ProblemError(f"unknown arm spec keys: {', '.join(unknown)}; known: {', '.join(SPEC_KEYS)}")
        return cls(**dict(spec))

    def spec(self) -> dict[str, Any]:
        """The full JSON-able spec; :meth:`from_spec` of it rebuilds an equal domain."""
        return {key: (list(value) if isinstance(value, list) else value) for key, value in self._spec.items()}

    @property
    def graph(self) -> ExplicitGraph:
        """The roadmap; ``vertex_states`` (V, 7) joint angles in radians."""
        return self._graph

    @property
    def start(self) -> int:
        """Start vertex (0)."""
        return 0

    @property
    def goal(self) -> int:
        """Goal vertex (1)."""
        return 1

    @property
    def world_models(self) -> tuple[str, ...]:
        """``("clutter", "table_clutter")``."""
        return WORLD_MODELS

    def make_world(self, model: str, seed: int) -> ArmWorld:
        """The world of ``model`` drawn with ``seed``; start and goal are free in it."""
        return sample_arm_world(model, seed, keep_clear=self.keep_clear)

    @staticmethod
    def world_from_scene(path: str | Path) -> ArmWorld:
        """A world from a MoveIt PlanningScene YAML file (boxes, cylinders, spheres)."""
        return world_from_planning_scene(path)

    def checker(self, world: ArmWorld | Scene, *, robot: RobotModel | None = None) -> ArmEdgeChecker:
        """An edge checker for a world (scene with the domain margin) or a ready scene (its own margin).

        Args:
            world: the obstacles.
            robot: another description of the same arm (see :meth:`robot_from_description`); its
                self-collision is then tested too, since the roadmap was pruned for :attr:`robot` only.
        """
        scene = world.to_scene(margin=self.margin) if isinstance(world, ArmWorld) else world
        if not isinstance(scene, Scene):
            raise ProblemError(f"arm checker needs an ArmWorld or a Scene, got {type(world).__name__}")
        other = robot is not None and robot is not self.robot
        return ArmEdgeChecker(
            robot=robot if robot is not None else self.robot,
            graph=self._graph,
            scene=scene,
            samples=self.samples,
            self_collision=other,
        )

    def robot_from_description(self, urdf: str, *, limits: MapLimits = MapLimits.DEFAULT) -> RobotModel:
        """The robot of a ``robot_description`` URDF text, checked against this domain's arm.

        Kinematics come from ``urdf``. Collision spheres come from ``urdf`` when its collision geometry
        is spheres, else from this domain's spherized model (a description with mesh collisions, as
        most robot stacks publish). Self-collision exclusions come from this domain's SRDF. The text's
        bytes, links and spheres are checked against ``limits`` before the model is built, its frames and
        spheres after (finite, within ``limits.max_coordinate``).

        Raises:
            ProblemError: invalid URDF, over a limit (the text names its parameter), coordinates not finite
                or too large, or a chain whose joints differ from this domain's.
        """
        check_description_size(urdf, limits)
        _, default_spheres, srdf = self._robot_texts
        try:
            robot = _robot_from_text(urdf, None, srdf)
        except GeometryError as own_spheres:
            if default_spheres is None:
                raise ProblemError(f"robot_description: {own_spheres}") from own_spheres
            try:
                robot = _robot_from_text(urdf, default_spheres, srdf)
            except GeometryError as exc:
                raise ProblemError(f"robot_description: {exc}") from exc
        want, got = self.robot.chain.joint_names, robot.chain.joint_names
        if got != want:
            raise ProblemError(
                f"robot_description has chain joints {list(got)}; the tree was built for {list(want)}"
            )
        check_robot_coordinates(robot, limits)
        return robot

    def end_effector_positions(self, q: npt.ArrayLike, robot: RobotModel | None = None) -> FloatArray:
        """(N, 3) tool-point position (m, root frame) for (N, D) configurations (rad).

        The tool point is the origin of the link rigidly attached to the last joint that lies farthest
        from it (``panda_grasptarget`` between the Panda's fingertips), so paths show where the gripper
        goes rather than the wrist.
        """
        model = robot if robot is not None else self.robot
        chain = model.chain
        attached = np.nonzero(chain.link_frames == chain.dof)[0]
        tool = int(attached[np.argmax(np.linalg.norm(chain.link_offsets[attached, :3, 3], axis=1))])
        return np.asarray(model.link_poses(q)[:, tool, :3, 3], dtype=np.float64)

    def edge_trajectories(self) -> None:
        """None: edges are straight lines in joint space."""
        return None

    def check_metadata(self) -> dict[str, Any]:
        """How edges are checked: sampling resolution (rad), margin (m), collision model."""
        return {
            "robot": self.robot.chain.robot_name,
            "joints": list(self.robot.chain.joint_names),
            "collision_model": "spheres",
            "spheres": self.robot.spheres.count,
            "resolution_rad": self.resolution,
            "resolution_meaning": "max joint step between consecutive samples of a straight joint-space edge",
            "sample_order": "end vertices, then interior samples in bisection order",
            "margin_m": self.margin,
            "floor_z_m": self._spec["floor_z"],
            "self_collision": "self-colliding configurations and edges are excluded from the roadmap",
            "edge_length": "joint-space Euclidean length (rad)",
            "interior_samples": int(self.samples.fractions.shape[0]),
        }


def _normalise_spec(spec: dict[str, Any]) -> dict[str, Any]:
    """Spec values converted to plain JSON types (TypeError/ValueError on bad values)."""

    def path(value: Any) -> str | None:
        return None if value is None else str(value)

    floor = spec["floor_z"]
    resolution = float(spec["resolution"])
    margin = float(spec["margin"])
    if not (math.isfinite(resolution) and resolution > 0):
        raise ValueError(f"resolution must be finite and > 0 rad, got {resolution}")
    if not (math.isfinite(margin) and margin >= 0):
        raise ValueError(f"margin must be finite and >= 0 m, got {margin}")
    out = {
        "urdf_path": path(spec["urdf_path"]),
        "sphere_urdf_path": path(spec["sphere_urdf_path"]),
        "srdf_path": path(spec["srdf_path"]),
        "start": [float(x) for x in spec["start"]],
        "goal": [float(x) for x in spec["goal"]],
        "num_samples": int(spec["num_samples"]),
        "k": int(spec["k"]),
        "seed": int(spec["seed"]),
        "resolution": resolution,
        "margin": margin,
        "floor_z": None if floor is None else float(floor),
    }
    return out
