"""The arm's edge checker: straight joint-space edges sampled at the check resolution, a collision model vs scene.

The end vertices of an edge are checked first (cached per world), then the interior samples in bisection
order, stopping at the first blocked sample. Forward kinematics is batched over all samples of an edge, and
in :meth:`ArmEdgeChecker.check_many` over all samples of many edges at once.

What "blocked" means is the checker's *collision model* (a :class:`ConfigurationTest`):

- :class:`SphereTest` (``collision_model: spheres``, the default): the spherized arm, every sphere grown by
  the scene margin, tested in two levels through the scene API (one bounding sphere per link first, then
  the spheres of the links whose bounding sphere touches something);
- :class:`~drd_planner.geometry.mesh_collider.MeshCollider` (``collision_model: meshes``, see
  :mod:`drd_planner.domains.arm_mesh_checker`): the URDF's collision meshes as FCL BVH models.

Both decide an edge's samples in the same order with the same early exit; self-collision (when asked for)
is the sphere model's in both.

**Motions off the roadmap** (:meth:`ArmEdgeChecker.check_motion`: a start or goal state joined to the roadmap,
an edge the planner grew) were never part of the roadmap's static test, so every sample of one is held to
the static rules first (joint limits, self-collision with the sphere model's pairs, and the floor when the
checker has a ``floor_z``), then to the scene. :meth:`ArmEdgeChecker.explain_motion` says what blocks one
(:mod:`drd_planner.domains.arm_explain`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.domains.arm_explain import explain_base, explain_configuration
from drd_planner.domains.arm_roadmap import EdgeSamples, graph_states, statically_valid
from drd_planner.domains.arm_robot import ROBOT_MODELS, RobotLoader
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.ordering import bisection_order
from drd_planner.geometry.robot import RobotModel
from drd_planner.geometry.scene import Scene

__all__ = ["CHECK_BLOCK", "ArmEdgeChecker", "ConfigurationTest", "SphereTest", "check_arm_edge"]

#: Interpolated configurations per forward-kinematics block in :meth:`ArmEdgeChecker.check_many`.
CHECK_BLOCK = 4096


class ConfigurationTest(Protocol):
    """A collision model of the arm against one scene: decides batches of configurations."""

    def base_free(self) -> bool:
        """Whether the parts fixed to the root link (the same in every configuration) are free."""
        ...

    def groups_blocked(self, q: FloatArray, owner: IntArray, count: int) -> BoolArray:
        """(count,) whether some configuration of each group hits the scene (moving parts only).

        Args:
            q: (N, D) configurations (rad); each group's rows consecutive and in check order.
            owner: (N,) int64 group of each row, non-decreasing, in ``[0, count)``.
            count: the number of groups.
        """
        ...


class SphereTest:
    """The sphere collision model: the robot's spheres, grown by the scene margin, against the scene.

    Args:
        robot: the robot (FK and spheres).
        scene: obstacles; its margin inflates every robot sphere.
    """

    def __init__(self, robot: RobotModel, scene: Scene) -> None:
        self.robot = robot
        self.scene = scene
        self._fixed = np.nonzero(robot.spheres.frame_index == 0)[0]
        self._moving_groups = np.nonzero(robot.groups.frame_index > 0)[0]
        self._group_radii = robot.groups.radii[self._moving_groups]
        self._base_free: bool | None = None

    def base_free(self) -> bool:
        """Whether the spheres fixed to the root link are free (cached)."""
        if self._base_free is None:
            if self._fixed.size == 0:
                self._base_free = True
            else:
                zero = np.zeros((1, self.robot.dof))
                centres = self.robot.sphere_centres(zero)[0, self._fixed]
                self._base_free = not self.scene.spheres_collide(centres, self.robot.spheres.radii[self._fixed])
        return self._base_free

    def _candidates(self, q: FloatArray) -> tuple[IntArray, IntArray, FloatArray]:
        """Spheres of (N, D) ``q`` whose link's bounding sphere touches the scene (first hierarchy level).

        Returns:
            ``(config, sphere, centres)``: for each of the C candidate spheres its configuration (row of
            ``q``), sphere index and (C, 3) centre (m), ordered by configuration.
        """
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

    def groups_blocked(self, q: FloatArray, owner: IntArray, count: int) -> BoolArray:
        """(count,) whether a moving sphere of some configuration of each group hits the scene.

        One group (one edge's interior) stops at the first blocked sphere in row order; several groups are
        decided together, every configuration of the batch at once.
        """
        blocked = np.zeros(count, dtype=bool)
        if q.shape[0] == 0:
            return blocked
        config, sphere, centres = self._candidates(q)
        if config.size == 0:
            return blocked
        radii = self.robot.spheres.radii[sphere]
        if count == 1:
            blocked[0] = self.scene.spheres_collide(centres, radii)
            return blocked
        hits = self.scene.spheres_collide_mask(centres, radii)
        blocked[np.unique(owner[config[hits]])] = True
        return blocked


class ArmEdgeChecker:
    """Checks the edges of a joint-space graph against one collision scene.

    Answers are cached: asking for an edge twice costs nothing the second time.

    Args:
        robot: the robot (FK, spheres, self-collision).
        graph: the roadmap; ``vertex_states`` (V, D) in radians.
        scene: obstacles; its margin applies.
        resolution: max joint step between samples (rad); ignored when ``samples`` is given.
        samples: precomputed :class:`EdgeSamples` of ``graph`` (shared between checkers of one domain).
        self_collision: also test self-collision of every sample (needed only for graphs not built by
            :func:`build_roadmap`, which already excludes self-colliding edges); the sphere model's test.
            Motions off the roadmap (:meth:`check_motion`) are always tested for it.
        model_for: the collision model of a scene (default: :class:`SphereTest` of ``robot``); the checker's
            model is ``model_for(scene)``, and explanations test one object at a time with it.
        floor_z: the roadmap's floor (m): no moving sphere of a motion off the roadmap may reach below it
            (None: no floor rule).

    Attributes:
        configurations_checked: configurations handed to the collision model so far.
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
        model_for: Callable[[Scene], ConfigurationTest] | None = None,
        floor_z: float | None = None,
    ) -> None:
        states = graph_states(graph)
        if states.shape[1] != robot.dof:
            raise ProblemError(f"graph states have {states.shape[1]} joints, the robot {robot.dof}")
        self.robot = robot
        self.graph = graph
        self.scene = scene
        self.samples = samples if samples is not None else EdgeSamples.of_graph(graph, resolution)
        self.self_collision = self_collision
        self.model_for: Callable[[Scene], ConfigurationTest] = (
            model_for if model_for is not None else (lambda other: SphereTest(robot, other))
        )
        self.model: ConfigurationTest = self.model_for(scene)
        self.floor_z = floor_z
        self._states = states
        self._edge_state = np.zeros(graph.num_edges, dtype=np.int8)  # 0 unknown, 1 free, -1 blocked
        self._vertex_state = np.zeros(graph.num_vertices, dtype=np.int8)
        self.configurations_checked = 0

    # ----------------------------------------------------------------------------------------------

    def _edge_ids(self, edges: npt.ArrayLike) -> IntArray:
        """Validated (K,) edge ids."""
        ids = np.asarray(edges, dtype=np.int64).reshape(-1)
        if ids.size and (ids.min() < 0 or ids.max() >= self.graph.num_edges):
            raise ProblemError(f"edge ids must lie in [0, {self.graph.num_edges})")
        return ids

    def _groups_blocked(self, q: FloatArray, owner: IntArray, count: int) -> BoolArray:
        """(count,) the collision model's answer for groups of configurations, self-collision added."""
        self.configurations_checked += q.shape[0]
        if self.self_collision and q.shape[0]:
            own = np.zeros(count, dtype=bool)
            own[np.unique(owner[self.robot.self_collision(q)])] = True
            if count == 1 and own[0]:
                return own
            blocked: BoolArray = own | self.model.groups_blocked(q, owner, count)
            return blocked
        return self.model.groups_blocked(q, owner, count)

    def _blocked_configs(self, q: FloatArray) -> BoolArray:
        """(N,) True where a configuration's moving parts hit the scene (or it self-collides)."""
        rows = np.arange(q.shape[0], dtype=np.int64)
        return self._groups_blocked(q, rows, q.shape[0])

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
        return not bool(self._groups_blocked(q, np.zeros(q.shape[0], dtype=np.int64), 1)[0])

    # ----------------------------------------------------------------------------------------------

    def _motion(self, states: npt.ArrayLike) -> FloatArray:
        """The validated (K, D) samples of a motion, in check order: both ends, then bisection order."""
        q = np.asarray(states, dtype=np.float64)
        if q.ndim != 2 or q.shape[0] < 1 or q.shape[1] != self._states.shape[1] or not np.all(np.isfinite(q)):
            raise ProblemError(f"a motion must be a finite (K, {self._states.shape[1]}) array, got {q.shape}")
        if q.shape[0] <= 2:
            return q
        order = np.concatenate([[0, q.shape[0] - 1], bisection_order(q.shape[0] - 2) + 1])
        return np.asarray(q[order], dtype=np.float64)

    def check_motion(self, states: npt.ArrayLike) -> bool:
        """True when a joint-space motion off the roadmap ((K, D) configurations, radians) is free.

        Every sample must pass the collision model (both ends first, then bisection order, stopping at the
        first blocked sample) and the static rules (joint limits, self-collision, the floor when ``floor_z`` is
        set). The samples must be as dense as the roadmap's check resolution (the planner's connector
        uses it).
        """
        q = self._motion(states)
        if not self.model.base_free():
            return False
        self.configurations_checked += q.shape[0]
        if self.model.groups_blocked(q, np.zeros(q.shape[0], dtype=np.int64), 1)[0]:
            return False  # the scene first: it stops at the first blocked sample, the static rules test all
        return bool(statically_valid(self.robot, q, floor_z=self.floor_z).all())

    def explain_motion(self, states: npt.ArrayLike) -> str:
        """What blocks a motion off the roadmap ((K, D) configurations, rad); "" when it is free.

        The first blocked sample in :meth:`check_motion`'s order and why (the static rule it breaks, or the
        scene objects that block it alone, with the link that meets each: :mod:`~drd_planner.domains.arm_explain`),
        e.g. ``scene object 'Can1' (panda_hand) at sample 3 of 21``; one sample: no "at sample" part.
        """
        raw = np.asarray(states, dtype=np.float64)
        q = self._motion(raw)
        if not self.model.base_free():
            return explain_base(self.scene, model_for=self.model_for) or "the robot's fixed base is blocked"
        rows = np.arange(q.shape[0], dtype=np.int64)
        blocked = ~statically_valid(self.robot, q, floor_z=self.floor_z) | self.model.groups_blocked(q, rows, len(q))
        if not blocked.any():
            return ""
        first = q[int(np.argmax(blocked))]
        why = explain_configuration(self.robot, self.scene, first, model_for=self.model_for, floor_z=self.floor_z)
        why = why or "the collision model"
        if q.shape[0] == 1:
            return why
        sample = int(np.flatnonzero(np.all(raw == first, axis=1))[0]) + 1
        return f"{why} at sample {sample} of {q.shape[0]}"

    def check(self, edge: int) -> bool:
        """True when ``edge`` is free: end vertices first, then interior samples in bisection order."""
        e = int(self._edge_ids([edge])[0])
        if self._edge_state[e] == 0:
            u, v = self.graph.edges[e]
            free = (
                self.model.base_free() and bool(self._vertices_free(np.array([u, v])).all()) and self._interior_free(e)
            )
            self._edge_state[e] = 1 if free else -1
        return bool(self._edge_state[e] > 0)

    def check_many(self, edges: npt.ArrayLike) -> BoolArray:
        """(K,) bool free flags of (K,) edge ids; the same answers as :meth:`check`, FK batched over edges."""
        ids = self._edge_ids(edges)
        todo = np.unique(ids[self._edge_state[ids] == 0])
        if todo.size:
            if not self.model.base_free():
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
            blocked = self._groups_blocked(q, owner, block.shape[0])
            self._edge_state[block] = np.where(blocked, -1, 1)
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
    loader: RobotLoader = ROBOT_MODELS,
) -> bool:
    """Whether one roadmap edge is free for the robot of a URDF string in ``scene`` (node-facing).

    Self-collision of every sample is tested as well (the graph may come from anywhere). The robot model
    is kept by ``loader`` per description text, so repeated calls only pay for the check.

    Args:
        urdf: URDF text (``robot_description``).
        scene: obstacles (its margin applies).
        graph: joint-space roadmap with (V, D) ``vertex_states`` in radians.
        edge: the edge id.
        resolution: max joint step between samples (rad).
        sphere_urdf: spherized URDF text when ``urdf`` has mesh collisions.
        srdf: SRDF text (self-collision exclusions).
        loader: where the robot model is built and kept.

    Raises:
        GeometryError: invalid descriptions.
        ProblemError: bad edge id or graph.
    """
    robot = loader.model(urdf, sphere_urdf, srdf)
    edge_graph = ExplicitGraph(
        graph.edges[[edge]] if 0 <= edge < graph.num_edges else graph.edges[:0],
        graph.lengths[[edge]] if 0 <= edge < graph.num_edges else graph.lengths[:0],
        graph.num_vertices,
        vertex_states=graph.vertex_states,
    )
    if edge_graph.num_edges != 1:
        raise ProblemError(f"edge id {edge} is not in [0, {graph.num_edges})")
    checker = ArmEdgeChecker(robot=robot, graph=edge_graph, scene=scene, resolution=resolution, self_collision=True)
    return checker.check(0)
