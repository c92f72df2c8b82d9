"""The planner's maps: named obstacles and terrain, versioned, turned into FCL scenes on demand.

Each accepted update makes a new :class:`MapSnapshot` (immutable, with a version number one higher);
a plan runs on the snapshot it started from, so a map arriving meanwhile never mixes two maps in one
plan. A snapshot's :class:`~drd_planner.geometry.scene.Scene` is built on first use, incrementally: it takes
the FCL objects of every obstacle that is unchanged since a snapshot whose scene is still kept (so a one-marker
update builds one object) and the terrain tiles of a terrain already built.

The scenes and terrain colliders are cached in a :class:`SceneCache` that a snapshot shares with every
snapshot made from it (``with_obstacles``, ``with_terrain``, ``with_robot``): whoever starts a lineage of
snapshots (a :class:`~drd_planner.planning.map_store.MapStore`) owns its cache. Memory stays bounded however
many snapshots callers keep (a node's plan history, say): only the scenes of the :data:`SCENE_CACHE_SIZE`
snapshots of a lineage asked for last, and the colliders of its :data:`COLLIDER_CACHE_SIZE` terrains asked for
last, are kept; an older snapshot that is asked again builds its scene again.
"""

from __future__ import annotations

import dataclasses
import threading
from collections import OrderedDict
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import TypeVar

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.geometry.aabb import shape_aabb
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.robot import RobotModel
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Shape
from drd_planner.geometry.terrain import Heightfield
from drd_planner.geometry.terrain_collider import TerrainCollider

K = TypeVar("K")
V = TypeVar("V")

#: Terrain colliders kept (the latest terrains asked for); each costs about 1.2 KiB per grid point.
COLLIDER_CACHE_SIZE = 2
#: Snapshot scenes kept (the latest snapshots asked for): the current map and the one before it.
SCENE_CACHE_SIZE = 2

Parts = tuple[tuple[Shape, Pose], ...]


def _cached(cache: OrderedDict[int, tuple[K, V]], key: K) -> V | None:
    """The value cached for ``key`` (marking it used), or None; call with the cache's lock held."""
    hit = cache.get(id(key))
    if hit is None or hit[0] is not key:
        return None
    cache.move_to_end(id(key))
    return hit[1]


def _make_room(cache: OrderedDict[int, tuple[K, V]], size: int) -> None:
    """Drop the least recently used entries until one more fits in ``size``; call with the lock held.

    Called before a new entry is built, so the entry being built and the ones kept never exceed ``size``
    at once (the peak memory of a map update is that of ``size`` terrains, not one more).
    """
    while len(cache) >= size:
        cache.popitem(last=False)


class SceneCache:
    """The FCL scenes and terrain colliders of one lineage of snapshots, least recently used first.

    An entry holds its key object (snapshot or heightfield), so the key's ``id`` cannot be reused while it
    is cached. Thread-safe: a map callback and the planning thread may ask at once.
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._colliders: OrderedDict[int, tuple[Heightfield, TerrainCollider]] = OrderedDict()
        self._scenes: OrderedDict[int, tuple[MapSnapshot, Scene]] = OrderedDict()

    def _store(self, cache: OrderedDict[int, tuple[K, V]], key: K, value: V, size: int) -> V:
        """Cache ``value`` for ``key`` unless another thread did first; returns the cached value."""
        with self._lock:
            found = _cached(cache, key)
            if found is not None:
                return found
            cache[id(key)] = (key, value)
            while len(cache) > size:
                cache.popitem(last=False)
        return value

    def terrain_collider(self, terrain: Heightfield) -> TerrainCollider:
        """The FCL tiles of ``terrain``, built once per heightfield object while it is among the latest terrains."""
        with self._lock:
            found = _cached(self._colliders, terrain)
            if found is None:
                _make_room(self._colliders, COLLIDER_CACHE_SIZE)
        if found is not None:
            return found
        return self._store(self._colliders, terrain, TerrainCollider(terrain), COLLIDER_CACHE_SIZE)

    def scene(self, snapshot: MapSnapshot) -> Scene:
        """The scene of ``snapshot``, built on first use from a kept scene of the same margin (the donor)."""
        with self._lock:
            found = _cached(self._scenes, snapshot)
            donor = next((pair for pair in reversed(self._scenes.values()) if pair[0].margin == snapshot.margin), None)
            if found is None:
                _make_room(self._scenes, SCENE_CACHE_SIZE)  # the newest scene stays (it is the donor)
        if found is not None:
            return found
        return self._store(self._scenes, snapshot, self._build_scene(snapshot, donor), SCENE_CACHE_SIZE)

    def _build_scene(self, snapshot: MapSnapshot, donor: tuple[MapSnapshot, Scene] | None) -> Scene:
        """The scene of ``snapshot``: a copy of the ``donor`` snapshot's scene with only what differs rebuilt.

        Obstacles are named ``"<key>#<part>"``; an obstacle whose parts are the same objects (or equal) in both
        snapshots keeps the donor's FCL objects, so the cost follows what changed (plus a dict copy).
        """
        if donor is None or (donor[0].terrain is not None and snapshot.terrain is None):
            scene = Scene(margin=snapshot.margin)
            old: Mapping[str, Parts] = {}
        else:
            scene, old = donor[1].copy(), donor[0].obstacles
        if snapshot.terrain is not None and (donor is None or snapshot.terrain is not donor[0].terrain):
            scene.add_terrain(snapshot.terrain, collider=self.terrain_collider(snapshot.terrain))
        new = snapshot.obstacles
        changed = [key for key in new if key not in old or (new[key] is not old[key] and new[key] != old[key])]
        for key in [key for key in old if key not in new] + [key for key in changed if key in old]:
            for k in range(len(old[key])):
                scene.remove(f"{key}#{k}")
        for key in sorted(changed):
            for k, (shape, pose) in enumerate(new[key]):
                scene.add(shape, pose, name=f"{key}#{k}")
        return scene


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
        cache: the scene cache of this snapshot's lineage (shared by the snapshots made from it).
    """

    version: int
    obstacles: Mapping[str, Parts] = field(default_factory=dict)
    terrain: Heightfield | None = None
    margin: float = 0.0
    robot: RobotModel | None = None
    obstacle_map: bool = False
    cache: SceneCache = field(default_factory=SceneCache, repr=False, compare=False)

    @property
    def has_maps(self) -> bool:
        """Whether any map (terrain or an obstacle map, even an empty one) has been received."""
        return self.terrain is not None or self.obstacle_map or bool(self.obstacles)

    @property
    def scene(self) -> Scene:
        """The FCL scene of this snapshot (built on first use, reusing what a kept scene already built)."""
        return self.cache.scene(self)

    def with_obstacles(self, obstacles: Mapping[str, Parts]) -> MapSnapshot:
        """The next version with ``obstacles`` replacing the obstacle map."""
        return dataclasses.replace(self, version=self.version + 1, obstacles=dict(obstacles), obstacle_map=True)

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

    A terrain counts as unchanged when its grid, heights (NaN = NaN) and unknown-height option are equal.

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
            and old.terrain.unknown == new.terrain.unknown
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
