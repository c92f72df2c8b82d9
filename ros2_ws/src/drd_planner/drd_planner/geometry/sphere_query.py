"""The scene's sphere query: packed obstacle arrays, cached FCL spheres, and the pairwise hit test.

:func:`sphere_hits` decides which spheres of a batch are blocked. A numpy AABB prefilter (and the terrain's grid
prefilter) picks the few sphere/obstacle pairs FCL must decide; the pairs are narrowphased in rank order with
one cached FCL sphere object per radius (moved with ``setTranslation``), and sphere centres inside closed
meshes count as hits too (FCL treats meshes as hollow surfaces).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import fcl
import numpy as np

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.geometry.aabb import spheres_overlap_aabbs
from drd_planner.geometry.fcl_queries import pair_collides
from drd_planner.geometry.solid import ClosedMesh
from drd_planner.geometry.terrain_collider import TerrainCollider

__all__ = ["SPHERE_CACHE_SIZE", "PackedObstacles", "SphereCache", "sphere_hits"]

#: Most cached FCL sphere objects (one per distinct query radius) before the cache is emptied.
SPHERE_CACHE_SIZE = 4096


@dataclass
class PackedObstacles:
    """Flat arrays of every non-terrain part (index n), then the terrain tiles (index n_obstacles + t).

    Attributes:
        objs: the FCL objects, obstacle parts first, then the terrain tiles.
        lo: (N, 3) AABB minima of the N obstacle parts in metres.
        hi: (N, 3) AABB maxima of the N obstacle parts in metres.
        points: (N, 3) a point inside each obstacle part in metres.
        solids: ``(index, closed mesh)`` of the parts that are watertight meshes.
    """

    objs: list[fcl.CollisionObject]
    lo: FloatArray
    hi: FloatArray
    points: FloatArray
    solids: list[tuple[int, ClosedMesh]] = field(default_factory=list)


class SphereCache:
    """One FCL sphere object per distinct radius, reused by every query (only its position changes)."""

    def __init__(self, size: int = SPHERE_CACHE_SIZE) -> None:
        self._size = size
        self._objects: dict[float, fcl.CollisionObject] = {}

    def __len__(self) -> int:
        return len(self._objects)

    def get(self, radius: float) -> fcl.CollisionObject:
        """The cached FCL sphere object of ``radius`` metres (its position is set by the caller).

        The cache is emptied when it holds ``size`` objects and a new radius arrives.
        """
        obj = self._objects.get(radius)
        if obj is None:
            if len(self._objects) >= self._size:
                self._objects.clear()
            obj = fcl.CollisionObject(fcl.Sphere(radius), fcl.Transform())
            self._objects[radius] = obj
        return obj


def sphere_hits(
    packed: PackedObstacles,
    terrain: TerrainCollider | None,
    cache: SphereCache,
    spheres: tuple[FloatArray, FloatArray],
    rank: IntArray | None,
    *,
    first: bool,
) -> BoolArray:
    """(K,) bool: which spheres are blocked; with ``first``, stops at one hit.

    Args:
        packed: the scene's obstacle arrays.
        terrain: the scene's terrain collider, or None.
        cache: the FCL sphere objects to reuse.
        spheres: ``(centres, radii)``: (K, 3) centres and (K,) margin-inflated radii in metres.
        rank: (K,) order in which the spheres' pairs are decided (index order when None).
        first: stop at the first blocked sphere (the other entries then stay False).
    """
    centres, radii = spheres
    hit = np.zeros(centres.shape[0], dtype=bool)
    if centres.shape[0] == 0:
        return hit
    ks, ns = spheres_overlap_aabbs(centres, radii, packed.lo, packed.hi)
    if terrain is not None:
        below, tk, tt = terrain.classify(centres, radii)
        if below.any():
            hit |= below
            if first:
                return hit
        if tk.size:
            ks = np.concatenate([ks, tk])
            ns = np.concatenate([ns, tt + packed.lo.shape[0]])
    if ks.size:
        order = np.argsort(ks if rank is None else rank[ks], kind="stable")
        ks, ns = ks[order], ns[order]
        if _decide_pairs((ks, ns), spheres, packed.objs, cache, hit, first=first):
            return hit
    _mark_inside_solids(packed.solids, (ks, ns), centres, hit, first=first)
    return hit


def _decide_pairs(
    pairs: tuple[IntArray, IntArray],
    spheres: tuple[FloatArray, FloatArray],
    objs: list[fcl.CollisionObject],
    cache: SphereCache,
    hit: BoolArray,
    *,
    first: bool,
) -> bool:
    """Narrowphase the (P,) sphere/object index ``pairs`` in order, marking ``hit``; True when stopped early.

    A sphere already hit is skipped; with ``first`` the loop stops at the first hit.
    """
    centres, radii = spheres
    current = -1
    sphere = None
    for k, n in zip(pairs[0].tolist(), pairs[1].tolist(), strict=True):
        if hit[k]:
            continue
        if k != current:
            sphere = cache.get(float(radii[k]))
            sphere.setTranslation(centres[k])
            current = k
        if pair_collides(sphere, objs[n]):
            hit[k] = True
            if first:
                return True
    return False


def _mark_inside_solids(
    solids: list[tuple[int, ClosedMesh]],
    pairs: tuple[IntArray, IntArray],
    centres: FloatArray,
    hit: BoolArray,
    *,
    first: bool,
) -> None:
    """Mark in ``hit`` the spheres not yet hit whose centre lies inside a closed mesh they are paired with.

    With ``first``, stops after the first closed mesh that contains a centre.
    """
    ks, ns = pairs
    for index, solid in solids:
        inside_candidates = ks[(ns == index) & ~hit[ks]]
        if inside_candidates.size:
            inside = inside_candidates[solid.contains(centres[inside_candidates])]
            hit[inside] = True
            if first and inside.size:
                return
