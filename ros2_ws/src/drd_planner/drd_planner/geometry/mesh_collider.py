"""A robot's collision meshes against a scene: which configurations are blocked, with early exit.

:class:`MeshCollider` places the robot's elements (:class:`~drd_planner.geometry.mesh_robot.MeshPlacement`) at
a batch of configurations and decides them in three levels:

1. numpy: the world AABB of every element at every configuration (one batched FK) against the AABBs of the
   scene's obstacle parts and terrain tiles, grown by the scene margin; elements whose box overlaps none are
   free;
2. FCL: each remaining element, in check order, is moved to its pose and collided against an FCL
   ``DynamicAABBTreeCollisionManager`` of the scene's objects, stopping at the first hit (its BVH against
   primitives, meshes and terrain tiles);
3. what FCL cannot see, because meshes are surfaces to it (the scene's own rules, see
   :class:`~drd_planner.geometry.scene.Scene`): an element under the terrain, an element inside a closed
   obstacle mesh, and an obstacle wholly inside a closed element (one point of the one inside the other).

**Margin.** With a scene margin m > 0 an element is also blocked when FCL's distance to an obstacle part
whose box lies within m of the element's box is below m (the Scene's rule for shapes it cannot inflate).
Distances between a BVH and a primitive cost about a millisecond each (collisions a few microseconds), so a
margin makes mesh checks much slower; the margin-0 check is the fast, exact one.

Each configuration group (an edge's samples) stops at its first blocked configuration; configurations are
decided in the order given (the caller puts an edge's samples in bisection order).
"""

from __future__ import annotations

from dataclasses import dataclass

import fcl
import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.geometry.aabb import boxes_overlap_box
from drd_planner.geometry.fcl_queries import first_hit, pair_collides, pair_contacts, pair_distance
from drd_planner.geometry.mesh_robot import MeshPlacement
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.solid import ClosedMesh
from drd_planner.geometry.terrain_collider import TerrainCollider

__all__ = ["MeshCollider", "MeshContact", "SceneObstacles"]

#: Configurations per block of the numpy box prefilter (bounds its (block, P, M) temporaries).
PREFILTER_BLOCK = 512
#: Contacts FCL reports per pair when measuring a penetration depth.
DEPTH_CONTACTS = 64


@dataclass(frozen=True)
class SceneObstacles:
    """The FCL objects of a scene and their boxes, as the mesh collider needs them.

    Attributes:
        objects: (M,) the scene's FCL objects: its N obstacle parts, then its terrain tiles (shared with the
            scene, never moved here).
        lo: (M, 3) AABB minima (m).
        hi: (M, 3) AABB maxima (m).
        points: (N, 3) a point inside each obstacle part (m).
        solids: ``(part index, closed mesh)`` of the parts that are watertight meshes.
        terrain: the scene's terrain collider, or None.
        margin: the scene margin (m).
    """

    objects: list[fcl.CollisionObject]
    lo: FloatArray
    hi: FloatArray
    points: FloatArray
    solids: list[tuple[int, ClosedMesh]]
    terrain: TerrainCollider | None
    margin: float

    @classmethod
    def of_scene(cls, scene: Scene) -> SceneObstacles:
        """The obstacles of ``scene`` as it is now (a later edit of the scene is not seen).

        Reads the scene's packed arrays (the ones its sphere queries use) and its terrain tiles.
        """
        packed = scene.packed_obstacles
        terrain = scene.terrain_collider
        lo, hi = packed.lo, packed.hi
        if terrain is not None:
            tile_lo, tile_hi = terrain.tile_boxes
            lo, hi = np.concatenate([lo, tile_lo]), np.concatenate([hi, tile_hi])
        return cls(list(packed.objs), lo, hi, packed.points, list(packed.solids), terrain, scene.margin)

    @property
    def parts(self) -> int:
        """N, the obstacle parts (the objects before the terrain tiles)."""
        return int(self.points.shape[0])


@dataclass(frozen=True)
class MeshContact:
    """Where a configuration is blocked (for reports).

    Attributes:
        row: the configuration (row of the queried array).
        part: the robot element (index into the placement's parts).
        link: its link name.
        obstacle: the scene object it meets (index into :attr:`SceneObstacles.objects`; -1 for the terrain
            surface test).
        reason: ``"contact"`` (FCL), ``"margin"`` (closer than the margin), ``"inside"`` (one inside the
            other) or ``"terrain"`` (under the terrain surface).
        depth: the deepest FCL penetration among the contacts (m; 0 for the other reasons).
        point: (3,) where that contact is, in the link's frame (m; NaN for the other reasons).
    """

    row: int
    part: int
    link: str
    obstacle: int
    reason: str
    depth: float
    point: FloatArray


class MeshCollider:
    """Decides configurations of a robot's elements against a scene's obstacles (see the module docstring).

    Args:
        placement: the robot's elements on its chain.
        obstacles: the scene's objects.

    Attributes:
        queries: elements moved and collided through FCL so far (level 2).
    """

    def __init__(self, placement: MeshPlacement, obstacles: SceneObstacles) -> None:
        self.placement = placement
        self.obstacles = obstacles
        self._objects = [fcl.CollisionObject(p.geometry, fcl.Transform()) for p in placement.meshes.parts]
        self._manager = fcl.DynamicAABBTreeCollisionManager()
        self._manager.registerObjects(obstacles.objects)
        self._manager.setup()
        self._moving: IntArray = np.nonzero(placement.frame_index > 0)[0]
        self._fixed: IntArray = np.nonzero(placement.frame_index == 0)[0]
        self._base_free: bool | None = None
        self.queries = 0

    # ----------------------------------------------------------------------------------------------

    def base_free(self) -> bool:
        """Whether the elements on the root link (the same in every configuration) are free (cached)."""
        if self._base_free is None:
            zero = np.zeros((1, self.placement.robot.dof))
            self._base_free = self._first_blocked(zero, self._fixed) is None
        return self._base_free

    def groups_blocked(self, q: npt.ArrayLike, owner: npt.ArrayLike, count: int) -> BoolArray:
        """(count,) whether some configuration of each group hits the scene (moving elements only).

        Args:
            q: (N, D) configurations; each group's rows consecutive and in check order.
            owner: (N,) group of each row, non-decreasing, in ``[0, count)``.
            count: the number of groups.

        A group stops at its first blocked configuration; its later rows are not decided.
        """
        qa = np.asarray(q, dtype=np.float64)
        groups = np.asarray(owner, dtype=np.int64)
        blocked = np.zeros(count, dtype=bool)
        if qa.shape[0] == 0 or self._moving.size == 0:
            return blocked
        poses, lo, hi, candidates = self._candidates(qa, self._moving)
        for r, c in zip(*np.nonzero(candidates), strict=True):
            g = groups[r]
            if not blocked[g] and self._decide(poses[r, c], int(self._moving[c]), lo[r, c], hi[r, c]):
                blocked[g] = True
                if count == 1:
                    break
        return blocked

    def base_contact(self) -> MeshContact | None:
        """Where the elements on the root link are blocked (row 0), or None when they are free."""
        return self._first_blocked(np.zeros((1, self.placement.robot.dof)), self._fixed)

    def first_contact(self, q: npt.ArrayLike) -> MeshContact | None:
        """Where the first blocked configuration of (N, D) ``q`` (in row order) is blocked, or None.

        Tests the moving elements only, like :meth:`groups_blocked`; the penetration depth is measured.
        """
        return self._first_blocked(np.asarray(q, dtype=np.float64), self._moving)

    # ----------------------------------------------------------------------------------------------

    def _candidates(self, q: FloatArray, parts: IntArray) -> tuple[FloatArray, FloatArray, FloatArray, BoolArray]:
        """Poses (N, P', 4, 4), boxes (N, P', 3) x 2 and the (N, P') elements level 1 cannot clear."""
        poses = self.placement.poses(q, parts)
        lo, hi = self.placement.boxes(poses, parts)
        margin = self.obstacles.margin
        near = np.zeros(lo.shape[:2], dtype=bool)
        obs_lo, obs_hi = self.obstacles.lo - margin, self.obstacles.hi + margin
        if obs_lo.shape[0]:
            for start in range(0, lo.shape[0], PREFILTER_BLOCK):
                a, b = (
                    lo[start : start + PREFILTER_BLOCK, :, None],
                    hi[start : start + PREFILTER_BLOCK, :, None],
                )
                overlap = np.all((a <= obs_hi) & (b >= obs_lo), axis=-1)
                near[start : start + PREFILTER_BLOCK] = overlap.any(axis=-1)
        terrain = self.obstacles.terrain
        if terrain is not None:  # an element wholly under the surface touches no tile box
            points = poses[..., :3, 3] + np.einsum("npij,pj->npi", poses[..., :3, :3], self._anchors(parts))
            near |= terrain.below(points.reshape(-1, 3)).reshape(near.shape)
        return poses, lo, hi, near

    def _anchors(self, parts: IntArray) -> FloatArray:
        """(P', 3) one vertex of each element in its own frame (for inside and under-terrain tests)."""
        return np.stack([self.placement.meshes.parts[int(p)].vertices[0] for p in parts])

    def _place(self, pose: FloatArray, part: int) -> fcl.CollisionObject:
        """The FCL object of element ``part`` moved to the (4, 4) ``pose``."""
        obj = self._objects[part]
        obj.setTransform(fcl.Transform(pose[:3, :3], pose[:3, 3]))
        return obj

    def _decide(self, pose: FloatArray, part: int, lo: FloatArray, hi: FloatArray) -> bool:
        """Whether element ``part`` at ``pose`` (world box ``lo``-``hi``) is blocked (levels 2 and 3)."""
        return self._why(pose, part, lo, hi) is not None

    def _why(self, pose: FloatArray, part: int, lo: FloatArray, hi: FloatArray) -> tuple[str, int] | None:
        """``(reason, obstacle)`` when element ``part`` at ``pose`` is blocked, else None.

        The obstacle is -1 where this test does not tell it (an FCL contact found by the broadphase, the
        terrain surface).
        """
        obj = self._place(pose, part)
        self.queries += 1
        if first_hit(self._manager, obj).hit:
            return "contact", -1
        obs = self.obstacles
        near = boxes_overlap_box(lo - obs.margin, hi + obs.margin, obs.lo, obs.hi)
        if obs.margin > 0.0:
            for k in near.tolist():
                if pair_distance(obj, obs.objects[k]) < obs.margin:
                    return "margin", k
        anchor = pose[:3, :3] @ self.placement.meshes.parts[part].vertices[0] + pose[:3, 3]
        if obs.terrain is not None and bool(obs.terrain.below(anchor[None])[0]):
            return "terrain", -1
        inside = self._inside(pose, part, lo, hi, near, anchor)
        return None if inside < 0 else ("inside", inside)

    def _inside(
        self, pose: FloatArray, part: int, lo: FloatArray, hi: FloatArray, near: IntArray, anchor: FloatArray
    ) -> int:
        """The obstacle part inside the closed element, or holding it inside its closed mesh; -1 if none."""
        obs = self.obstacles
        near_parts = near[near < obs.parts]
        solid = self.placement.meshes.parts[part].solid
        if solid is not None and near_parts.size:
            points = obs.points[near_parts]
            within = near_parts[np.all((points >= lo) & (points <= hi), axis=1)]
            if within.size:
                local = (obs.points[within] - pose[:3, 3]) @ pose[:3, :3]
                hits = np.asarray(solid.contains(local), dtype=bool)
                if hits.any():
                    return int(within[np.argmax(hits)])
        near_set = set(near_parts.tolist())
        for index, closed in obs.solids:
            if index in near_set and bool(closed.contains(anchor[None])[0]):
                return index
        return -1

    def _first_blocked(self, q: FloatArray, parts: IntArray) -> MeshContact | None:
        """The first blocked (row, element) of ``q`` among ``parts``, with where and how deep."""
        if parts.size == 0 or q.shape[0] == 0:
            return None
        poses, lo, hi, candidates = self._candidates(q, parts)
        for r, c in zip(*np.nonzero(candidates), strict=True):
            part = int(parts[c])
            why = self._why(poses[r, c], part, lo[r, c], hi[r, c])
            if why is not None:
                reason, obstacle = why
                depth, point = 0.0, np.full(3, np.nan)
                element = self.placement.meshes.parts[part]
                if reason == "contact":
                    obstacle, depth, world = self._deepest(self._objects[part], lo[r, c], hi[r, c])
                    pose = poses[r, c]
                    local = pose[:3, :3].T @ (world - pose[:3, 3])  # in the element's frame
                    point = element.origin[:3, :3] @ local + element.origin[:3, 3]
                return MeshContact(int(r), part, element.link, obstacle, reason, depth, point)
        return None

    def _deepest(self, obj: fcl.CollisionObject, lo: FloatArray, hi: FloatArray) -> tuple[int, float, FloatArray]:
        """``(obstacle, depth, point)``: what ``obj`` meets with the deepest FCL contact, how deep (m), where."""
        best, depth, where = -1, -1.0, np.full(3, np.nan)
        for k in boxes_overlap_box(lo, hi, self.obstacles.lo, self.obstacles.hi).tolist():
            other = self.obstacles.objects[k]
            if not pair_collides(obj, other):
                continue
            for contact in pair_contacts(obj, other, DEPTH_CONTACTS):
                if float(contact.penetration_depth) > depth:
                    best, depth = k, float(contact.penetration_depth)
                    where = np.asarray(contact.pos, dtype=np.float64)
        return best, max(depth, 0.0), where
