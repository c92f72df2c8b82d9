"""The numpy sphere/box prefilter against a brute-force reference."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.geometry.aabb import spheres_overlap_aabbs


def brute_force(centres: np.ndarray, radii: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> set[tuple[int, int]]:
    pairs = set()
    for k, (c, r) in enumerate(zip(centres, radii, strict=True)):
        for n, (a, b) in enumerate(zip(lo, hi, strict=True)):
            if np.all(c + r >= a) and np.all(c - r <= b):
                pairs.add((k, n))
    return pairs


@pytest.mark.parametrize(("count", "chunk"), [(1, 16), (15, 16), (16, 16), (37, 16), (37, 1), (50, 7)])
def test_prefilter_equals_brute_force(count: int, chunk: int) -> None:
    rng = np.random.default_rng(count * 100 + chunk)
    centres = np.cumsum(rng.normal(scale=0.4, size=(count, 3)), axis=0)  # trajectory-like, spatially coherent
    radii = rng.uniform(0.05, 0.5, size=count)
    lo = rng.uniform(-4, 4, size=(30, 3))
    hi = lo + rng.uniform(0.1, 2.0, size=(30, 3))
    ks, ns = spheres_overlap_aabbs(centres, radii, lo, hi, chunk=chunk)
    got = set(zip(ks.tolist(), ns.tolist(), strict=True))
    assert len(got) == ks.size  # no duplicates
    assert got == brute_force(centres, radii, lo, hi)


def test_touching_boxes_overlap_and_empty_inputs() -> None:
    lo = np.array([[1.0, -1.0, -1.0]])
    hi = np.array([[2.0, 1.0, 1.0]])
    ks, ns = spheres_overlap_aabbs(np.array([[0.5, 0.0, 0.0], [0.4, 0.0, 0.0]]), np.array([0.5, 0.5]), lo, hi)
    assert (ks.tolist(), ns.tolist()) == ([0], [0])
    ks, ns = spheres_overlap_aabbs(np.zeros((0, 3)), np.zeros(0), lo, hi)
    assert ks.size == ns.size == 0
    ks, ns = spheres_overlap_aabbs(np.zeros((3, 3)), np.ones(3), np.zeros((0, 3)), np.zeros((0, 3)))
    assert ks.size == ns.size == 0
