"""The 7-DoF arm domain: a joint-space roadmap of the Franka Panda, its worlds and edge checks (spheres or meshes).

Pieces (one concept per module):

- :mod:`~drd_planner.domains.arm_params`: the spec (:class:`~drd_planner.domains.arm_params.ArmParams`);
- :mod:`~drd_planner.domains.arm_robot`: the robot files and the cache of parsed models;
- :mod:`~drd_planner.domains.arm_roadmap`: the statically valid k-nearest roadmap and its edge samples;
- :mod:`~drd_planner.domains.arm_checker`: the edge checker (end vertices, then bisection order);
- :mod:`~drd_planner.domains.arm_sweep`: the sweep model for re-checking plans after a map update.

Defaults (Panda; 600 Halton samples, k = 8, resolution 0.05 rad): 489 vertices and 2475 edges, about
31 interior samples per edge. Start and goal (:data:`DEFAULT_START`, :data:`DEFAULT_GOAL`) hold the
gripper low over the front left and front right of the table, so objects on the table often block the
direct start-goal edge (1.6 rad, the shortest path) and the arm must lift over or reach around them.

The robot model is read from the shared Panda files (``<shared data>/panda``,
:func:`drd_planner.settings.shared_data_dir`) unless the spec names other files.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.domains.arm_checker import ArmEdgeChecker
from drd_planner.domains.arm_description import check_description_size, check_robot_coordinates
from drd_planner.domains.arm_mesh_checker import (
    arm_link_meshes,
    mesh_metadata,
    mesh_model,
    mesh_sweep_growth,
)
from drd_planner.domains.arm_params import DEFAULT_GOAL, DEFAULT_START, SPEC_KEYS, ArmParams
from drd_planner.domains.arm_roadmap import EdgeSamples, build_roadmap
from drd_planner.domains.arm_robot import ROBOT_MODELS, RobotLoader, default_panda_dir, robot_texts
from drd_planner.domains.arm_sweep import ArmSweep
from drd_planner.domains.arm_worlds import (
    WORLD_MODELS,
    ArmWorld,
    KeepClear,
    sample_arm_world,
    world_from_planning_scene,
)
from drd_planner.domains.online import (
    EdgeSource,
    OnlineDefaults,
    PositionGoals,
    RobotStateTopic,
    SweepSpheres,
)
from drd_planner.exceptions import GeometryError, PlanningError, ProblemError
from drd_planner.geometry.map_limits import MapLimits
from drd_planner.geometry.mesh_collider import MeshCollider
from drd_planner.geometry.robot import RobotModel
from drd_planner.geometry.scene import Scene

#: Clearance (m) added to the robot's spheres at start and goal when placing random obstacles.
KEEP_CLEAR_CLEARANCE = 0.02

__all__ = [
    "DEFAULT_GOAL",
    "DEFAULT_START",
    "SPEC_KEYS",
    "ArmDomain",
    "ArmParams",
    "default_panda_dir",
]


class ArmDomain(OnlineDefaults):
    """The arm domain (registry name ``"arm"``): Panda roadmap, world models and edge checks.

    World checks use the spherized model (``collision_model: spheres``, the default: fast) or FCL BVH
    meshes of the URDF's collision geometry (``meshes``, as MoveIt; see
    :mod:`~drd_planner.domains.arm_mesh_checker`).

    Implements :class:`~drd_planner.domains.online.OnlineDomain` (worlds: :class:`ArmWorld`). From
    :class:`~drd_planner.domains.online.OnlineDefaults` it keeps: no vehicle sphere (the arm is checked as
    its sphere model), no periodic dimensions (joint angles are bounded by their limits) and no world model
    parameters in the spec.

    Args:
        params: the spec (default :class:`ArmParams`).
        loader: where robot models are built and kept (shared by default, so equal descriptions give
            one model object).

    Raises:
        ProblemError: invalid values, unreadable or invalid robot files, a start, goal or extra state that
            is not statically valid (the failing check and parameter named) or repeated, or one not connected
            to the start.
    """

    name = "arm"

    def __init__(self, params: ArmParams | None = None, *, loader: RobotLoader = ROBOT_MODELS) -> None:
        p = params if params is not None else ArmParams()
        self._params = p
        self.loader = loader
        try:
            self._robot_texts = robot_texts(p.urdf_path, p.sphere_urdf_path, p.srdf_path)
            self._robot = loader.model(*self._robot_texts)
        except GeometryError as exc:
            raise ProblemError(f"arm robot model: {exc}") from exc
        self._graph = build_roadmap(self._robot, p)
        self.samples = EdgeSamples.of_graph(self._graph, p.resolution)
        self._sweep = ArmSweep(self._graph, self.samples)
        ends = np.array([p.start, p.goal], dtype=np.float64)
        centres = self._robot.sphere_centres(ends).reshape(-1, 3)
        radii = np.tile(self._robot.spheres.radii, 2) + p.margin + KEEP_CLEAR_CLEARANCE
        self.keep_clear = KeepClear(centres, radii)

    @classmethod
    def from_spec(cls, spec: Mapping[str, Any]) -> ArmDomain:
        """The domain of a spec (:class:`ArmParams` keys; missing keys take the defaults).

        Raises:
            ProblemError: unknown keys (the valid ones named) or invalid values.
        """
        return cls(ArmParams.from_spec(spec))

    def spec(self) -> dict[str, Any]:
        """The full JSON-able spec; :meth:`from_spec` of it rebuilds an equal domain."""
        return self._params.to_spec()

    @property
    def params(self) -> ArmParams:
        """The domain's parameters."""
        return self._params

    @property
    def robot(self) -> RobotModel:
        """The arm model the roadmap was built for."""
        return self._robot

    @property
    def resolution(self) -> float:
        """Max joint step between the checked samples of an edge (rad)."""
        return float(self._params.resolution)

    @property
    def margin(self) -> float:
        """Safety distance added to every robot sphere in world checks (m)."""
        return float(self._params.margin)

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
    def extra_vertices(self) -> range:
        """The vertices of the spec's ``extra_states``: vertex ``2 + i`` is ``extra_states[i]``."""
        return range(2, 2 + len(self._params.extra_states))

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

        The collision model is the spec's ``collision_model``: the spheres, or the URDF's collision meshes
        (:mod:`~drd_planner.domains.arm_mesh_checker`; placed by ``robot``'s kinematics when given).

        Args:
            world: the obstacles.
            robot: another description of the same arm (see :meth:`robot_from_description`); its
                self-collision is then tested too, since the roadmap was pruned for :attr:`robot` only.

        Raises:
            ProblemError: not a world or scene, or collision meshes that cannot be read.
        """
        scene = world.to_scene(margin=self.margin) if isinstance(world, ArmWorld) else world
        if not isinstance(scene, Scene):
            raise ProblemError(f"arm checker needs an ArmWorld or a Scene, got {type(world).__name__}")
        arm = robot if robot is not None else self._robot
        model_for = None
        if self._params.collision_model == "meshes":
            meshes = arm_link_meshes(self._params, self._robot_texts[0])

            def model_for(other: Scene) -> MeshCollider:
                return mesh_model(arm, other, meshes)

        return ArmEdgeChecker(
            robot=arm,
            graph=self._graph,
            scene=scene,
            samples=self.samples,
            self_collision=arm is not self._robot,
            model_for=model_for,
            floor_z=self._params.floor_z,
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
            robot = self.loader.model(urdf, None, srdf)
        except GeometryError as own_spheres:
            if default_spheres is None:
                raise ProblemError(f"robot_description: {own_spheres}") from own_spheres
            try:
                robot = self.loader.model(urdf, default_spheres, srdf)
            except GeometryError as exc:
                raise ProblemError(f"robot_description: {exc}") from exc
        want, got = self._robot.chain.joint_names, robot.chain.joint_names
        if got != want:
            raise ProblemError(f"robot_description has chain joints {list(got)}; the tree was built for {list(want)}")
        check_robot_coordinates(robot, limits)
        return robot

    def end_effector_positions(self, q: npt.ArrayLike, robot: RobotModel | None = None) -> FloatArray:
        """(N, 3) tool-point position (m, root frame) for (N, D) configurations (rad).

        The tool point is the origin of the link rigidly attached to the last joint that lies farthest
        from it (``panda_grasptarget`` between the Panda's fingertips), so paths show where the gripper
        goes rather than the wrist.
        """
        model = robot if robot is not None else self._robot
        chain = model.chain
        attached = np.nonzero(chain.link_frames == chain.dof)[0]
        tool = int(attached[np.argmax(np.linalg.norm(chain.link_offsets[attached, :3, 3], axis=1))])
        return np.asarray(model.link_poses(q)[:, tool, :3, 3], dtype=np.float64)

    def edge_trajectories(self) -> None:
        """None: edges are straight lines in joint space."""
        return None

    def check_metadata(self) -> dict[str, Any]:
        """How edges are checked: sampling resolution (rad), margin (m), collision model (with its meshes)."""
        meshes = (
            mesh_metadata(arm_link_meshes(self._params, self._robot_texts[0]))
            if self._params.collision_model == "meshes"
            else {}
        )
        return {
            "robot": self._robot.chain.robot_name,
            "joints": list(self._robot.chain.joint_names),
            "collision_model": self._params.collision_model,
            **meshes,
            "spheres": self._robot.spheres.count,
            "resolution_rad": self.resolution,
            "resolution_meaning": "max joint step between consecutive samples of a straight joint-space edge",
            "sample_order": "end vertices, then interior samples in bisection order",
            "margin_m": self.margin,
            "floor_z_m": self._params.floor_z,
            "self_collision": "self-colliding configurations and edges are excluded from the roadmap",
            "edge_length": "joint-space Euclidean length (rad)",
            "interior_samples": int(self.samples.fractions.shape[0]),
        }

    # ------------------------------------------------------------------------------------------------
    # Online domain

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The chain joint names, root to tip (states are joint vectors)."""
        return tuple(self._robot.chain.joint_names)

    @property
    def position_goals(self) -> PositionGoals:
        """``"vertex"``: a goal position is the roadmap vertex whose tool point is nearest."""
        return "vertex"

    @property
    def plans_joint_goals(self) -> bool:
        """True: goals and starts are joint vectors (a start pose is refused)."""
        return True

    @property
    def robot_state_topic(self) -> RobotStateTopic:
        """``"joint_states"``: the arm's state is its joint angles."""
        return "joint_states"

    @property
    def publishes_joint_trajectory(self) -> bool:
        """True: a plan goes out as a JointTrajectory, and its Path is the tool point's."""
        return True

    @property
    def needs_robot_description(self) -> bool:
        """True: tool points and checks use the ``robot_description`` model when one was received."""
        return True

    @property
    def state_columns(self) -> str:
        """Joint angles."""
        return "joint angles, rad"

    @property
    def has_sweep_model(self) -> bool:
        """True (:mod:`~drd_planner.domains.arm_sweep`)."""
        return True

    def positions(self, states: npt.ArrayLike, robot: RobotModel | None = None) -> FloatArray:
        """(K, 3) tool-point positions (m) of (K, D) configurations (:meth:`end_effector_positions`)."""
        return self.end_effector_positions(states, robot)

    def scene_checker(self, scene: Scene, robot: RobotModel | None = None) -> ArmEdgeChecker:
        """The edge checker of a ready scene, with another arm model when given (see :meth:`checker`)."""
        return self.checker(scene) if robot is None else self.checker(scene, robot=robot)

    def robot_loader(self) -> Callable[[str], RobotModel]:
        """:meth:`robot_from_description` (with the default limits)."""
        return self.robot_from_description

    def state_from_position(self, xyz: npt.ArrayLike, yaw: float) -> FloatArray:
        """Refused: a goal position is matched to a roadmap vertex (:attr:`position_goals` is ``"vertex"``).

        Raises:
            PlanningError: always.
        """
        raise PlanningError("the arm domain matches goal positions to roadmap vertices")

    def sweep_robot(self, robot: RobotModel | None) -> RobotModel | None:
        """``robot`` when it is another model than the domain's own, else None."""
        return robot if robot is not self._robot else None

    def sweep_spheres(self, source: EdgeSource, edges: Sequence[int], robot: RobotModel | None) -> SweepSpheres:
        """Per edge every robot sphere at every checked configuration, grown by half a sample step.

        Under the mesh model (``collision_model: meshes``) every sphere also grows by
        :func:`~drd_planner.domains.arm_mesh_checker.mesh_sweep_growth`, so the swept spheres contain the
        link meshes the checker tests (the meshes reach up to about 8 cm outside the Panda's spheres).
        """
        model = robot if robot is not None else self._robot
        growth = (
            mesh_sweep_growth(model, arm_link_meshes(self._params, self._robot_texts[0]))
            if self._params.collision_model == "meshes"
            else None
        )
        return self._sweep.spheres(source, edges, model, growth)
