"""The planner's maps: named obstacles and terrain, versioned, turned into FCL scenes on demand.

Each accepted update makes a new :class:`MapSnapshot` (immutable, with a version number one higher);
a plan runs on the snapshot it started from, so a map arriving meanwhile never mixes two maps in one
plan. Snapshots build their :class:`~drd_planner.geometry.scene.Scene` once, lazily.
"""

from __future__ import annotations

import dataclasses
import weakref
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import numpy.typing as npt

from drd_planner.geometry.aabb import shape_aabb
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.robot import RobotModel
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Shape
from drd_planner.geometry.terrain import Heightfield
from drd_planner.geometry.terrain_collider import TerrainCollider

FloatArray = npt.NDArray[np.float64]

#: Terrain colliders by heightfield object: snapshots that keep the terrain (an obstacle update) share it.
_COLLIDERS: weakref.WeakKeyDictionary[Heightfield, TerrainCollider] = weakref.WeakKeyDictionary()


def terrain_collider(terrain: Heightfield) -> TerrainCollider:
    """The FCL tiles of ``terrain``, built once per heightfield object (most of a scene's build time)."""
    collider = _COLLIDERS.get(terrain)
    if collider is None:
        collider = _COLLIDERS[terrain] = TerrainCollider(terrain)
    return collider


Parts = tuple[tuple[Shape, Pose], ...]


@dataclass(frozen=True, eq=False)
class MapSnapshot:
    """One version of the maps.

    Attributes:
        version: 0 for the empty map, +1 per accepted update.
        obstacles: key (``ns/id``) -> collision parts in the planning frame (metres).
        terrain: the terrain heightfield, or None before one arrived.
        margin: collision margin of the scene, metres.
        robot: the arm of the latest ``robot_description`` (None: the tree's own model).
        obstacle_map: an obstacle map has been received (an empty one is a valid map: a clear table).
    """

    version: int
    obstacles: Mapping[str, Parts] = field(default_factory=dict)
    terrain: Heightfield | None = None
    margin: float = 0.0
    robot: RobotModel | None = None
    obstacle_map: bool = False

    @property
    def has_maps(self) -> bool:
        """Whether any map (terrain or an obstacle map, even an empty one) has been received."""
        return self.terrain is not None or self.obstacle_map or bool(self.obstacles)

    @cached_property
    def scene(self) -> Scene:
        """The FCL scene of this snapshot (built on first use)."""
        scene = Scene(margin=self.margin)
        if self.terrain is not None:
            scene.add_terrain(self.terrain, collider=terrain_collider(self.terrain))
        for key in sorted(self.obstacles):
            for k, (shape, pose) in enumerate(self.obstacles[key]):
                scene.add(shape, pose, name=f"{key}#{k}")
        return scene

    def with_obstacles(self, obstacles: Mapping[str, Parts]) -> MapSnapshot:
        """The next version with ``obstacles`` replacing the obstacle map."""
        return dataclasses.replace(
            self, version=self.version + 1, obstacles=dict(obstacles), obstacle_map=True
        )

    def with_terrain(self, terrain: Heightfield) -> MapSnapshot:
        """The next version with ``terrain``."""
        return dataclasses.replace(self, version=self.version + 1, terrain=terrain)

    def with_robot(self, robot: RobotModel) -> MapSnapshot:
        """The next version with the arm of a new ``robot_description``."""
        return dataclasses.replace(self, version=self.version + 1, robot=robot)


def obstacle_boxes(parts: Iterable[tuple[Shape, Pose]]) -> tuple[FloatArray, FloatArray]:
    """(lo, hi) (N, 3) axis-aligned boxes of ``parts`` in metres (N = 0 gives empty arrays)."""
    boxes = [shape_aabb(shape, pose) for shape, pose in parts]
    if not boxes:
        return np.zeros((0, 3)), np.zeros((0, 3))
    return np.array([b[0] for b in boxes]), np.array([b[1] for b in boxes])


def changed_parts(old: MapSnapshot, new: MapSnapshot) -> list[tuple[Shape, Pose]] | None:
    """Parts that appeared, changed or disappeared between two snapshots; None if the terrain or robot changed.

    A replan only has to re-check the plan's edges that come near one of these parts (removed ones
    cannot block anything, but they are reported so callers can tell "nothing changed" apart).
    """
    if old.robot is not new.robot:
        return None
    if old.terrain is not new.terrain:
        same = (
            old.terrain is not None
            and new.terrain is not None
            and old.terrain.shape == new.terrain.shape
            and old.terrain.cell_size == new.terrain.cell_size
            and np.array_equal(old.terrain.origin, new.terrain.origin)
            and np.array_equal(old.terrain.heights, new.terrain.heights, equal_nan=True)
        )
        if not same:
            return None
    out: list[tuple[Shape, Pose]] = []
    for key in set(old.obstacles) | set(new.obstacles):
        a, b = old.obstacles.get(key), new.obstacles.get(key)
        if a != b:
            out.extend(b or ())
            out.extend(a or ())
    return out
