"""Seeded world models of the arm domain, and worlds from MoveIt planning scenes.

A world is a tuple of posed primitives (:class:`~drd_planner.geometry.moveit_scene.ScenePrimitive`) in the
robot's root frame (z up, the robot base at the origin, "in front" = +x). Models:

- ``"clutter"``: 4-9 boxes (edges 0.05-0.25 m) and cylinders (radius 0.02-0.08 m, length 0.1-0.4 m),
  each with a uniformly random orientation and its centre uniform in x 0.2-0.8 m, y -0.7-0.7 m,
  z 0.05-0.9 m.
- ``"table_clutter"``: a table top (0.6-0.9 m deep, 1.0-1.6 m wide, 0.04 m thick) whose near edge is
  0.3-0.5 m from the base in the direction (azimuth) -0.35-0.35 rad, its top 0.0-0.2 m above the base,
  turned by up to 0.2 rad about z against that direction, on four 0.05 m legs, plus 8-16 upright boxes
  (footprint edges 0.03-0.2 m, height 0.15-0.45 m) and cylinders (radius 0.02-0.06 m, height 0.1-0.35 m)
  standing on the top with random yaw.

No obstacle may touch the keep-clear spheres (the robot at its start and goal configurations,
inflated by a clearance): such draws are repeated (the table up to 100 times, each object up to 30
times, then dropped), so start and goal are free in every world. Same (model, seed, keep-clear), same
world.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from drd_planner.arrays import FloatArray
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.moveit_scene import ScenePrimitive, parse_planning_scene, read_planning_scene
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Box, Cylinder, Pose

WORLD_MODELS: tuple[str, ...] = ("clutter", "table_clutter")

CLUTTER_COUNT = (4, 9)
CLUTTER_BOX_EDGE = (0.05, 0.25)
CLUTTER_CYLINDER_RADIUS = (0.02, 0.08)
CLUTTER_CYLINDER_LENGTH = (0.1, 0.4)
CLUTTER_REGION = ((0.2, 0.8), (-0.7, 0.7), (0.05, 0.9))

TABLE_DEPTH = (0.6, 0.9)
TABLE_WIDTH = (1.0, 1.6)
TABLE_THICKNESS = 0.04
TABLE_NEAR_EDGE = (0.3, 0.5)
TABLE_AZIMUTH = (-0.35, 0.35)
TABLE_TOP_HEIGHT = (0.0, 0.2)
TABLE_TURN = (-0.2, 0.2)
TABLE_LEG = 0.05
TABLE_OBJECTS = (8, 16)
TABLE_BOX_FOOTPRINT = (0.03, 0.2)
TABLE_BOX_HEIGHT = (0.15, 0.45)
TABLE_CYLINDER_RADIUS = (0.02, 0.06)
TABLE_CYLINDER_HEIGHT = (0.1, 0.35)
#: Objects keep this far (m) inside the table top's edges.
TABLE_INSET = 0.05

TABLE_TRIES = 100
OBJECT_TRIES = 30

__all__ = [
    "WORLD_MODELS",
    "ArmWorld",
    "KeepClear",
    "sample_arm_world",
    "world_from_planning_scene",
]


@dataclass(frozen=True)
class KeepClear:
    """Spheres no obstacle may touch.

    Attributes:
        centres: (K, 3) sphere centres in the root frame (m).
        radii: (K,) radii (m), clearance included.
    """

    centres: FloatArray
    radii: FloatArray

    def blocked_by(self, primitive: ScenePrimitive) -> bool:
        """Whether ``primitive`` touches any of the spheres."""
        if self.radii.shape[0] == 0:
            return False
        scene = Scene()
        scene.add(primitive.shape, primitive.pose, name=primitive.name)
        return scene.spheres_collide(self.centres, self.radii)


@dataclass(frozen=True)
class ArmWorld:
    """One world of the arm domain: posed primitives in the robot's root frame.

    Attributes:
        obstacles: the primitives (names unique).
        model: the world model name (or ``"moveit"`` for an imported planning scene).
        seed: the seed it was drawn with (None for imported scenes).
    """

    obstacles: tuple[ScenePrimitive, ...]
    model: str
    seed: int | None = None

    def to_scene(self, *, margin: float = 0.0) -> Scene:
        """A collision :class:`Scene` with every obstacle, inflating queries by ``margin`` metres."""
        scene = Scene(margin=margin)
        for obstacle in self.obstacles:
            scene.add(obstacle.shape, obstacle.pose, name=obstacle.name)
        return scene


def world_from_planning_scene(source: str | Path, *, is_text: bool = False) -> ArmWorld:
    """An :class:`ArmWorld` from a MoveIt PlanningScene YAML file (or its text with ``is_text``).

    Raises:
        GeometryError: the scene has something the importer cannot represent (see
            :mod:`drd_planner.geometry.moveit_scene`).
    """
    primitives = parse_planning_scene(str(source)) if is_text else read_planning_scene(source)
    return ArmWorld(obstacles=primitives, model="moveit", seed=None)


# --------------------------------------------------------------------------------------------------
# Sampling helpers


def _uniform(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    """One draw from U[bounds]."""
    return float(rng.uniform(bounds[0], bounds[1]))


def _yaw(angle: float) -> FloatArray:
    """(4,) xyzw quaternion of a rotation by ``angle`` rad about +z."""
    return np.array([0.0, 0.0, math.sin(angle / 2.0), math.cos(angle / 2.0)])


def _place(
    rng: np.random.Generator, keep_clear: KeepClear, draw: Callable[[], ScenePrimitive], tries: int
) -> ScenePrimitive | None:
    """The first of up to ``tries`` draws that leaves the keep-clear spheres free (None if none does)."""
    for _ in range(tries):
        candidate = draw()
        if not keep_clear.blocked_by(candidate):
            return candidate
    return None


def _clutter(rng: np.random.Generator, keep_clear: KeepClear) -> list[ScenePrimitive]:
    """The obstacles of a ``"clutter"`` world."""
    count = int(rng.integers(CLUTTER_COUNT[0], CLUTTER_COUNT[1] + 1))
    out: list[ScenePrimitive] = []
    for i in range(count):
        is_box = bool(rng.random() < 0.5)

        def draw(is_box: bool = is_box, i: int = i) -> ScenePrimitive:
            centre = [_uniform(rng, axis) for axis in CLUTTER_REGION]
            quat = Rotation.random(random_state=rng).as_quat()
            if is_box:
                return ScenePrimitive(f"box_{i}", Box(rng.uniform(*CLUTTER_BOX_EDGE, size=3)), Pose(centre, quat))
            shape = Cylinder(_uniform(rng, CLUTTER_CYLINDER_RADIUS), _uniform(rng, CLUTTER_CYLINDER_LENGTH))
            return ScenePrimitive(f"cylinder_{i}", shape, Pose(centre, quat))

        placed = _place(rng, keep_clear, draw, OBJECT_TRIES)
        if placed is not None:
            out.append(placed)
    return out


def _table(rng: np.random.Generator) -> tuple[list[ScenePrimitive], Pose, FloatArray]:
    """A table (top + legs), the top's pose and its (3,) size."""
    depth, width = _uniform(rng, TABLE_DEPTH), _uniform(rng, TABLE_WIDTH)
    azimuth, near = _uniform(rng, TABLE_AZIMUTH), _uniform(rng, TABLE_NEAR_EDGE)
    top_z = _uniform(rng, TABLE_TOP_HEIGHT)
    yaw = azimuth + _uniform(rng, TABLE_TURN)
    distance = near + depth / 2.0
    centre = np.array([distance * math.cos(azimuth), distance * math.sin(azimuth), top_z - TABLE_THICKNESS / 2])
    size = np.array([depth, width, TABLE_THICKNESS])
    top_pose = Pose(centre, _yaw(yaw))
    parts = [ScenePrimitive("table_top", Box(size), top_pose)]
    leg_height = top_z - TABLE_THICKNESS
    if leg_height > 0.01:
        rot = top_pose.rotation()
        for name, sx, sy in (("fl", -1, 1), ("fr", -1, -1), ("bl", 1, 1), ("br", 1, -1)):
            local = np.array([sx * (depth - TABLE_LEG) / 2, sy * (width - TABLE_LEG) / 2, 0.0])
            xy = centre + rot @ local
            pose = Pose([xy[0], xy[1], leg_height / 2.0], _yaw(yaw))
            parts.append(ScenePrimitive(f"table_leg_{name}", Box([TABLE_LEG, TABLE_LEG, leg_height]), pose))
    return parts, top_pose, size


def _table_clutter(rng: np.random.Generator, keep_clear: KeepClear) -> list[ScenePrimitive]:
    """The obstacles of a ``"table_clutter"`` world."""
    for _ in range(TABLE_TRIES):
        table, top_pose, size = _table(rng)
        if not any(keep_clear.blocked_by(part) for part in table):
            break
    else:
        raise ProblemError(f"no table pose in {TABLE_TRIES} draws leaves the start and goal free")
    top_z = float(top_pose.position[2]) + TABLE_THICKNESS / 2
    rot = top_pose.rotation()
    half = size[:2] / 2 - TABLE_INSET
    out = list(table)
    count = int(rng.integers(TABLE_OBJECTS[0], TABLE_OBJECTS[1] + 1))
    for i in range(count):
        is_box = bool(rng.random() < 0.5)

        def draw(is_box: bool = is_box, i: int = i) -> ScenePrimitive:
            local = np.array([rng.uniform(-half[0], half[0]), rng.uniform(-half[1], half[1]), 0.0])
            xy = top_pose.position + rot @ local
            quat = _yaw(float(rng.uniform(-math.pi, math.pi)))
            if is_box:
                footprint = rng.uniform(*TABLE_BOX_FOOTPRINT, size=2)
                height = _uniform(rng, TABLE_BOX_HEIGHT)
                pose = Pose([xy[0], xy[1], top_z + height / 2], quat)
                return ScenePrimitive(f"box_{i}", Box([footprint[0], footprint[1], height]), pose)
            radius, height = _uniform(rng, TABLE_CYLINDER_RADIUS), _uniform(rng, TABLE_CYLINDER_HEIGHT)
            pose = Pose([xy[0], xy[1], top_z + height / 2], quat)
            return ScenePrimitive(f"cylinder_{i}", Cylinder(radius, height), pose)

        placed = _place(rng, keep_clear, draw, OBJECT_TRIES)
        if placed is not None:
            out.append(placed)
    return out


def sample_arm_world(model: str, seed: int, *, keep_clear: KeepClear) -> ArmWorld:
    """The world of ``model`` drawn with ``seed`` (``numpy.random.default_rng``).

    Args:
        model: one of :data:`WORLD_MODELS`.
        seed: the world's seed.
        keep_clear: spheres no obstacle may touch (the robot at start and goal).

    Raises:
        ProblemError: unknown model, or no table pose leaves start and goal free.
    """
    if model not in WORLD_MODELS:
        raise ProblemError(f"unknown arm world model {model!r}; choose one of {', '.join(WORLD_MODELS)}")
    rng = np.random.default_rng(seed)
    obstacles = _clutter(rng, keep_clear) if model == "clutter" else _table_clutter(rng, keep_clear)
    return ArmWorld(obstacles=tuple(obstacles), model=model, seed=int(seed))
