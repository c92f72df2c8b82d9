"""Tests of the scene's sphere query: packed obstacles, the FCL sphere cache and the pairwise hit test."""

import fcl
import numpy as np

from drd_planner.geometry.sphere_query import PackedObstacles, SphereCache, sphere_hits


def _box(centre: tuple[float, float, float], half: float) -> tuple[fcl.CollisionObject, np.ndarray, np.ndarray]:
    obj = fcl.CollisionObject(fcl.Box(2 * half, 2 * half, 2 * half), fcl.Transform(np.array(centre, dtype=float)))
    c = np.array(centre, dtype=float)
    return obj, c - half, c + half


def _packed(*boxes: tuple[fcl.CollisionObject, np.ndarray, np.ndarray]) -> PackedObstacles:
    return PackedObstacles(
        objs=[b[0] for b in boxes],
        lo=np.array([b[1] for b in boxes]).reshape(-1, 3),
        hi=np.array([b[2] for b in boxes]).reshape(-1, 3),
        points=np.array([(b[1] + b[2]) / 2 for b in boxes]).reshape(-1, 3),
    )


def test_cache_reuses_one_object_per_radius_and_empties_when_full() -> None:
    cache = SphereCache(size=2)
    a = cache.get(0.5)
    assert cache.get(0.5) is a
    cache.get(1.0)
    assert len(cache) == 2
    cache.get(2.0)  # a third radius empties the full cache first
    assert len(cache) == 1
    assert cache.get(0.5) is not a


def test_hits_mask_and_first_hit() -> None:
    packed = _packed(_box((0.0, 0.0, 0.0), 1.0), _box((10.0, 0.0, 0.0), 1.0))
    centres = np.array([[0.0, 0.0, 1.5], [5.0, 0.0, 0.0], [10.0, 0.0, -1.2], [20.0, 0.0, 0.0]])
    radii = np.array([0.6, 1.0, 0.3, 1.0])
    cache = SphereCache()
    mask = sphere_hits(packed, None, cache, (centres, radii), None, first=False)
    np.testing.assert_array_equal(mask, [True, False, True, False])
    first = sphere_hits(packed, None, cache, (centres, radii), None, first=True)
    np.testing.assert_array_equal(first, [True, False, False, False])
    # With a rank, the pairs of the best-ranked sphere are decided first.
    ranked = sphere_hits(packed, None, cache, (centres, radii), np.array([3, 2, 0, 1]), first=True)
    np.testing.assert_array_equal(ranked, [False, False, True, False])


def test_no_spheres_and_no_obstacles() -> None:
    cache = SphereCache()
    empty = sphere_hits(_packed(), None, cache, (np.zeros((0, 3)), np.zeros(0)), None, first=True)
    assert empty.shape == (0,)
    free = sphere_hits(_packed(), None, cache, (np.zeros((2, 3)), np.ones(2)), None, first=False)
    np.testing.assert_array_equal(free, [False, False])
