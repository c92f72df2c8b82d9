"""A collision scene: named obstacles, optional terrain, and the edge-check queries the planner calls.

Obstacles are posed primitives and meshes (:meth:`Scene.add`), sagging wires (:meth:`Scene.add_wire`, a chain
of capsules) and one terrain (:meth:`Scene.add_terrain`). Every query inflates by the scene's ``margin``: an
object is blocked when its distance to any obstacle is below ``margin`` metres. Besides FCL's surface contacts
every query also reports as blocked

- objects wholly under the terrain (their centre under the triangulated surface), and
- objects wholly inside a closed (watertight) mesh obstacle (trimesh ``contains``),

because FCL treats meshes, and so terrain, as hollow surfaces.

Speed: sphere queries never build FCL objects per call. One FCL sphere object per distinct radius is cached
and moved with ``setTranslation``; a numpy AABB prefilter (and a grid prefilter for terrain) picks the few
sphere/obstacle pairs FCL must decide, and the narrowphase stops at the first hit.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import fcl
import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.exceptions import GeometryError
from drd_planner.geometry.aabb import boxes_overlap_box, shape_aabb
from drd_planner.geometry.fcl_queries import first_hit, pair_distance
from drd_planner.geometry.ordering import bisection_rank
from drd_planner.geometry.pose import Pose, as_points
from drd_planner.geometry.shapes import Capsule, Shape, Sphere, TriangleMesh, make_fcl_geometry, shape_point
from drd_planner.geometry.solid import ClosedMesh, closed_mesh
from drd_planner.geometry.sphere_query import PackedObstacles, SphereCache, sphere_hits
from drd_planner.geometry.terrain import Heightfield
from drd_planner.geometry.terrain_collider import TerrainCollider
from drd_planner.geometry.wires import Wire

__all__ = ["Scene"]


@dataclass
class _Part:
    """One FCL object of an obstacle, with its world AABB and a point inside it."""

    obj: fcl.CollisionObject
    lo: FloatArray
    hi: FloatArray
    point: FloatArray
    solid: ClosedMesh | None = None


@dataclass
class _Entry:
    """A named obstacle: one shape, a wire's capsule chain, or the terrain's tiles."""

    kind: Literal["shape", "wire", "terrain"]
    parts: list[_Part]
    shape: Shape | None = None
    shared: bool = False  # its parts (FCL objects) also belong to another scene: never move them in place


class Scene:
    """Named obstacles and terrain with fast collision queries.

    Args:
        margin: safety distance in metres (>= 0); queries report objects closer than this as blocked.
    """

    def __init__(self, *, margin: float = 0.0) -> None:
        margin_m = float(margin)
        if not np.isfinite(margin_m) or margin_m < 0.0:
            raise GeometryError(f"scene margin must be finite and >= 0, got {margin!r}")
        self._margin = margin_m
        self._entries: dict[str, _Entry] = {}
        self._terrain: TerrainCollider | None = None
        self._terrain_name: str | None = None
        self._manager: fcl.DynamicAABBTreeCollisionManager | None = None  # built by the first collides()
        self._manager_dirty = False
        self._version = 0
        self._packed: PackedObstacles | None = None
        self._counter = 0
        self._spheres = SphereCache()

    # ------------------------------------------------------------------------------------------------
    # State

    @property
    def margin(self) -> float:
        """Safety distance in metres included in every query."""
        return self._margin

    @property
    def version(self) -> int:
        """Counter bumped by every change (add, remove, move, clear); caches keyed on it stay valid."""
        return self._version

    @property
    def names(self) -> tuple[str, ...]:
        """Names of all obstacles (the terrain included), in insertion order."""
        return tuple(self._entries)

    @property
    def terrain(self) -> Heightfield | None:
        """The terrain, or None."""
        return None if self._terrain is None else self._terrain.heightfield

    @property
    def packed_obstacles(self) -> PackedObstacles:
        """The flat obstacle arrays the sphere queries use (rebuilt after changes; read-only by convention)."""
        return self._pack()

    @property
    def terrain_collider(self) -> TerrainCollider | None:
        """The terrain's FCL tiles, or None."""
        return self._terrain

    @property
    def bounds(self) -> tuple[FloatArray, FloatArray] | None:
        """``(lo, hi)``, each (3,) in metres: the AABB of everything in the scene (without margin); None if empty."""
        packed = self._pack()
        los = [packed.lo] if packed.lo.shape[0] else []
        his = [packed.hi] if packed.hi.shape[0] else []
        if self._terrain is not None:
            lo, hi = self._terrain.bounds
            los.append(lo[None])
            his.append(hi[None])
        if not los:
            return None
        return np.concatenate(los).min(axis=0), np.concatenate(his).max(axis=0)

    def __contains__(self, name: object) -> bool:
        return name in self._entries

    def __len__(self) -> int:
        return len(self._entries)

    # ------------------------------------------------------------------------------------------------
    # Editing

    def add(self, shape: Shape, pose: Pose, *, name: str | None = None, replace: bool = False) -> str:
        """Add ``shape`` at ``pose``; returns its name (``name``, or a fresh ``"obstacle_<n>"``).

        A watertight :class:`TriangleMesh` is treated as a solid (inside = blocked); any other mesh as a surface.

        Raises:
            GeometryError: ``name`` is taken and ``replace`` is False, or the shape is invalid.
        """
        key = self._claim(name, "obstacle", replace=replace)
        part = self._make_part(shape, pose)
        self._insert(key, _Entry("shape", [part], shape=shape))
        return key

    def add_wire(
        self, wire: Wire, *, segments: int | None = None, name: str | None = None, replace: bool = False
    ) -> str:
        """Add a wire as its capsule chain (:meth:`Wire.capsule_chain` with ``segments``); returns its name."""
        key = self._claim(name, "wire", replace=replace)
        parts = [self._make_part(capsule, pose) for capsule, pose in wire.capsule_chain(segments)]
        self._insert(key, _Entry("wire", parts))
        return key

    def add_terrain(
        self,
        heightfield: Heightfield,
        *,
        tile_cells: int = 8,
        name: str = "terrain",
        collider: TerrainCollider | None = None,
    ) -> str:
        """Set the terrain (replacing any previous one); returns its name.

        Args:
            heightfield: the terrain grid in metres.
            tile_cells: cells per side of each FCL mesh tile.
            name: the terrain's obstacle name.
            collider: a ready collider of ``heightfield`` to share (its FCL tiles never move, so several
                scenes may hold them); built here when None.

        Raises:
            GeometryError: ``collider`` belongs to another heightfield.
        """
        if collider is None:
            collider = TerrainCollider(heightfield, tile_cells=tile_cells)
        elif collider.heightfield is not heightfield:
            raise GeometryError("the given terrain collider was built for another heightfield")
        if self._terrain_name is not None:
            self.remove(self._terrain_name)
        key = self._claim(name, "terrain", replace=False)
        tile_lo, tile_hi = collider.tile_boxes
        parts = [_Part(obj, lo, hi, lo) for obj, lo, hi in zip(collider.objects, tile_lo, tile_hi, strict=True)]
        self._insert(key, _Entry("terrain", parts))
        self._terrain = collider
        self._terrain_name = key
        return key

    def copy(self) -> Scene:
        """A scene with the same margin, obstacles and terrain sharing their FCL objects: a dict copy, no geometry.

        Moving a shared obstacle later in either scene first gives that scene its own object.
        """
        new = Scene(margin=self._margin)
        for entry in self._entries.values():
            entry.shared = True
        new._entries = dict(self._entries)
        new._terrain, new._terrain_name, new._counter = self._terrain, self._terrain_name, self._counter
        new._packed = self._packed  # read-only arrays; dropped by the copy's first edit
        return new

    def alone(self, name: str) -> Scene:
        """A scene with the same margin holding only obstacle ``name`` (its FCL objects shared, as :meth:`copy`).

        For saying which obstacle blocks something: query each obstacle alone.

        Raises:
            GeometryError: no such obstacle.
        """
        entry = self._entries.get(name)
        if entry is None:
            raise GeometryError(f"no obstacle named {name!r} in the scene")
        entry.shared = True
        new = Scene(margin=self._margin)
        new._entries = {name: entry}
        if name == self._terrain_name:
            new._terrain, new._terrain_name = self._terrain, name
        return new

    def set_pose(self, name: str, pose: Pose) -> None:
        """Move the shape obstacle ``name`` to ``pose`` (FCL's broadphase is updated at once).

        Raises:
            GeometryError: no such obstacle, or it is a wire or the terrain.
        """
        entry = self._entries.get(name)
        if entry is None or entry.kind != "shape" or entry.shape is None:
            raise GeometryError(f"no movable shape obstacle named {name!r} in the scene")
        if entry.shared:  # another scene holds the same FCL object: this one gets its own
            self.remove(name)
            self._insert(name, _Entry("shape", [self._make_part(entry.shape, pose)], shape=entry.shape))
            return
        part = entry.parts[0]
        part.obj.setTransform(pose.to_fcl())
        if self._manager is not None:
            self._manager.update(part.obj)
        fresh = self._make_part(entry.shape, pose, obj=part.obj)
        part.lo, part.hi, part.point, part.solid = fresh.lo, fresh.hi, fresh.point, fresh.solid
        self._changed()

    def remove(self, name: str) -> None:
        """Remove obstacle ``name``.

        Raises:
            GeometryError: no such obstacle.
        """
        entry = self._entries.pop(name, None)
        if entry is None:
            raise GeometryError(f"no obstacle named {name!r} in the scene")
        if self._manager is not None:
            for part in entry.parts:
                self._manager.unregisterObject(part.obj)
        if name == self._terrain_name:
            self._terrain = None
            self._terrain_name = None
        self._manager_dirty = True
        self._changed()

    def clear(self) -> None:
        """Remove everything (the margin stays)."""
        self._entries.clear()
        self._terrain = None
        self._terrain_name = None
        self._manager = None
        self._manager_dirty = False
        self._changed()

    # ------------------------------------------------------------------------------------------------
    # Queries

    def collides(self, shape: Shape, pose: Pose) -> bool:
        """Whether ``shape`` at ``pose`` is blocked.

        Blocked means closer than the margin to an obstacle, under the terrain, or inside a closed mesh. Uses
        FCL's broadphase with a callback that stops at the first hit.
        """
        if not isinstance(pose, Pose):
            raise GeometryError(f"pose must be a Pose, got {type(pose).__name__}")
        query = fcl.CollisionObject(make_fcl_geometry(self._inflated(shape)), pose.to_fcl())
        if first_hit(self._broadphase(), query).hit:
            return True
        packed = self._pack()
        lo, hi = shape_aabb(shape, pose)
        lo, hi = lo - self._margin, hi + self._margin
        near = boxes_overlap_box(lo, hi, packed.lo, packed.hi)
        if self._within_margin(shape, query, np.concatenate([near, self._terrain_tiles(lo, hi)])):
            return True
        return self._inside_something(shape, pose, near)

    def spheres_collide(self, centres: npt.ArrayLike, radii: npt.ArrayLike | float) -> bool:
        """Whether any of the spheres is blocked (stops at the first blocked sphere).

        Args:
            centres: (K, 3) sphere centres in metres.
            radii: a radius or (K,) radii in metres (> 0); the scene margin is added.
        """
        points = as_points(centres, what="sphere centres")
        return bool(self._sphere_hits(points, self._radii(radii, points.shape[0]), None, first=True).any())

    def spheres_collide_mask(self, centres: npt.ArrayLike, radii: npt.ArrayLike | float) -> BoolArray:
        """(K,) bool: which of the (K, 3) spheres (radius or (K,) radii, metres) are blocked."""
        points = as_points(centres, what="sphere centres")
        return self._sphere_hits(points, self._radii(radii, points.shape[0]), None, first=False)

    def sphere_sweep_free(self, points: npt.ArrayLike, radius: npt.ArrayLike | float) -> bool:
        """Whether a sphere (or a set of spheres) is free at every sample along a trajectory.

        Samples are checked in bisection order (middle first) and the check stops at the first hit; motion
        between samples is not checked (sample finely enough for the radius).

        Args:
            points: (K, 3) sphere centres along the trajectory, or (K, S, 3): S spheres (e.g. of a robot) at
                each of K configurations; metres.
            radius: a radius, or radii broadcastable to ``points.shape[:-1]`` (e.g. (S,) per robot sphere);
                metres, > 0; the scene margin is added.
        """
        array = np.asarray(points, dtype=np.float64)
        if array.ndim == 3 and array.shape[2] == 3:
            steps, per_step = array.shape[0], array.shape[1]
        elif array.ndim == 2 and array.shape[1] == 3:
            steps, per_step = array.shape[0], 1
        else:
            raise GeometryError(f"sweep points must have shape (K, 3) or (K, S, 3), got {array.shape}")
        try:
            radii = np.broadcast_to(np.asarray(radius, dtype=np.float64), array.shape[:-1]).reshape(-1)
        except ValueError as exc:
            raise GeometryError(f"sweep radius must broadcast to {array.shape[:-1]}: {exc}") from exc
        centres = as_points(array.reshape(-1, 3), what="sweep points")
        rank = (bisection_rank(steps)[:, None] * per_step + np.arange(per_step)).reshape(-1)
        return not bool(self._sphere_hits(centres, self._radii(radii, centres.shape[0]), rank, first=True).any())

    # ------------------------------------------------------------------------------------------------
    # Internals

    def _sphere_hits(self, centres: FloatArray, radii: FloatArray, rank: IntArray | None, *, first: bool) -> BoolArray:
        """(K,) bool hits of spheres with margin-inflated (K,) ``radii``; with ``first``, stops at one hit.

        Pairs are decided in increasing ``rank`` of their sphere (index order when None).
        """
        return sphere_hits(self._pack(), self._terrain, self._spheres, (centres, radii), rank, first=first)

    def _inflated(self, shape: Shape) -> Shape:
        """``shape`` grown by the margin when it is a sphere or capsule (FCL then decides the margin exactly)."""
        if self._margin > 0.0 and isinstance(shape, Sphere):
            return Sphere(shape.radius + self._margin)
        if self._margin > 0.0 and isinstance(shape, Capsule):
            return Capsule(shape.radius + self._margin, shape.length)
        return shape

    def _broadphase(self) -> fcl.DynamicAABBTreeCollisionManager:
        """FCL's broadphase of every obstacle part, built on first use and updated after changes."""
        if self._manager is None:  # only collides() needs the broadphase: built on first use
            self._manager = fcl.DynamicAABBTreeCollisionManager()
            self._manager.registerObjects([p.obj for e in self._entries.values() for p in e.parts])
            self._manager_dirty = True
        if self._manager_dirty:
            self._manager.update()
            self._manager_dirty = False
        return self._manager

    def _within_margin(self, shape: Shape, query: fcl.CollisionObject, candidates: IntArray) -> bool:
        """Whether a shape that :meth:`_inflated` cannot grow is closer than the margin to a candidate part.

        Args:
            shape: the query shape (spheres and capsules were inflated already: always False for them).
            query: its FCL object.
            candidates: packed indices of the obstacle parts and terrain tiles near it.
        """
        if self._margin <= 0.0 or isinstance(shape, Sphere | Capsule):
            return False
        objs = self._pack().objs
        return any(pair_distance(query, objs[n]) < self._margin for n in candidates.tolist())

    def _inside_something(self, shape: Shape, pose: Pose, near: IntArray) -> bool:
        """Whether ``shape`` at ``pose`` is under the terrain, inside a closed mesh, or holds a near obstacle.

        Args:
            shape: the query shape.
            pose: its pose.
            near: packed indices of the obstacle parts whose margin-grown AABB overlaps the shape's.
        """
        packed = self._pack()
        point = shape_point(shape, pose)[None]
        if self._terrain is not None and bool(self._terrain.below(point)[0]):
            return True
        near_set = set(near.tolist())
        if any(index in near_set and bool(solid.contains(point)[0]) for index, solid in packed.solids):
            return True
        if isinstance(shape, TriangleMesh) and near.size:
            own = closed_mesh(shape, pose)
            return own is not None and bool(own.contains(packed.points[near]).any())
        return False

    def _radii(self, radii: npt.ArrayLike | float, count: int) -> FloatArray:
        """(count,) radii plus the margin; GeometryError unless each radius is finite and > 0."""
        if isinstance(radii, float | int):
            if not 0.0 < radii < np.inf:
                raise GeometryError(f"sphere radius must be finite and > 0, got {radii!r}")
            return np.full(count, radii + self._margin)
        try:
            array = np.broadcast_to(np.asarray(radii, dtype=np.float64), (count,))
        except ValueError as exc:
            raise GeometryError(f"sphere radii must be a number or have shape ({count},): {exc}") from exc
        if not (np.isfinite(array).all() and (array > 0.0).all()):
            raise GeometryError("sphere radii must be finite and > 0")
        inflated: FloatArray = array + self._margin
        return inflated

    def _terrain_tiles(self, lo: FloatArray, hi: FloatArray) -> IntArray:
        """Packed indices of the terrain tiles whose AABB overlaps the box ``lo``-``hi`` (metres)."""
        if self._terrain is None:
            return np.zeros(0, dtype=np.int64)
        tile_lo, tile_hi = self._terrain.tile_boxes
        offset = self._pack().lo.shape[0]
        tiles: IntArray = boxes_overlap_box(lo, hi, tile_lo, tile_hi) + offset
        return tiles

    def _pack(self) -> PackedObstacles:
        """The flat obstacle arrays, rebuilt after changes."""
        if self._packed is not None:
            return self._packed
        parts = [part for entry in self._entries.values() if entry.kind != "terrain" for part in entry.parts]
        objs = [part.obj for part in parts]
        if self._terrain is not None:
            objs.extend(self._terrain.objects)
        packed = PackedObstacles(
            objs=objs,
            lo=np.array([p.lo for p in parts]).reshape(-1, 3),
            hi=np.array([p.hi for p in parts]).reshape(-1, 3),
            points=np.array([p.point for p in parts]).reshape(-1, 3),
            solids=[(index, part.solid) for index, part in enumerate(parts) if part.solid is not None],
        )
        self._packed = packed
        return packed

    def _make_part(self, shape: Shape, pose: Pose, *, obj: fcl.CollisionObject | None = None) -> _Part:
        """The FCL object (new unless ``obj`` is given), world AABB, inside point and solid test of a shape."""
        if not isinstance(pose, Pose):
            raise GeometryError(f"pose must be a Pose, got {type(pose).__name__}")
        if obj is None:
            obj = fcl.CollisionObject(make_fcl_geometry(shape), pose.to_fcl())
        lo, hi = shape_aabb(shape, pose)
        solid = closed_mesh(shape, pose) if isinstance(shape, TriangleMesh) else None
        return _Part(obj, lo, hi, shape_point(shape, pose), solid)

    def _claim(self, name: str | None, prefix: str, *, replace: bool) -> str:
        """A free obstacle name: ``name`` (removing its old obstacle when ``replace``) or a fresh one."""
        if name is None:
            while True:
                self._counter += 1
                candidate = f"{prefix}_{self._counter}"
                if candidate not in self._entries:
                    return candidate
        if not isinstance(name, str) or not name:
            raise GeometryError(f"obstacle name must be a non-empty string, got {name!r}")
        if name in self._entries:
            if not replace:
                raise GeometryError(f"an obstacle named {name!r} is already in the scene")
            self.remove(name)
        return name

    def _insert(self, name: str, entry: _Entry) -> None:
        """Register ``entry``'s objects with the broadphase (once it exists) and record it."""
        if self._manager is not None:
            self._manager.registerObjects([part.obj for part in entry.parts])
            self._manager_dirty = True
        self._entries[name] = entry
        self._changed()

    def _changed(self) -> None:
        """Bump the version and drop derived caches."""
        self._version += 1
        self._packed = None
