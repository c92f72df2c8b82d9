"""World-frame axis-aligned bounding boxes of posed shapes, and the vectorised overlap prefilter.

An AABB is a pair ``(lo, hi)`` of (3,) arrays in metres. The boxes here are tight for primitives (exact for
boxes, spheres, cylinders and capsules under any rotation) so that the numpy prefilter hands FCL few pairs.
"""

from __future__ import annotations

import numpy as np

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.exceptions import GeometryError
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Box, Capsule, Cylinder, Shape, Sphere, TriangleMesh

#: Spheres per chunk in the two-level prefilter of :func:`spheres_overlap_aabbs`.
SPHERE_CHUNK = 16

__all__ = ["boxes_overlap_box", "shape_aabb", "spheres_overlap_aabbs"]


def shape_aabb(shape: Shape, pose: Pose) -> tuple[FloatArray, FloatArray]:
    """``(lo, hi)``, each (3,) in metres: the smallest world AABB of ``shape`` placed at ``pose``.

    Raises:
        GeometryError: ``shape`` is not a shape type.
    """
    centre = np.array(pose.position)
    if isinstance(shape, TriangleMesh):
        world = pose.transform_points(shape.vertices[np.unique(shape.faces)])
        return world.min(axis=0), world.max(axis=0)
    rot = pose.rotation()
    if isinstance(shape, Box):
        half = np.abs(rot) @ (shape.size / 2.0)
    elif isinstance(shape, Sphere):
        half = np.full(3, shape.radius)
    elif isinstance(shape, Cylinder):
        axis = rot[:, 2]
        # A disc of radius r with unit normal a spans r * sqrt(1 - a_i^2) along world axis i.
        half = np.abs(axis) * shape.length / 2.0 + shape.radius * np.sqrt(np.clip(1.0 - axis**2, 0.0, 1.0))
    elif isinstance(shape, Capsule):
        half = np.abs(rot[:, 2]) * shape.length / 2.0 + shape.radius
    else:
        raise GeometryError(f"not a collision shape: {type(shape).__name__}")
    return centre - half, centre + half


def spheres_overlap_aabbs(
    centres: FloatArray, radii: FloatArray, lo: FloatArray, hi: FloatArray, *, chunk: int = SPHERE_CHUNK
) -> tuple[IntArray, IntArray]:
    """Index pairs ``(k, n)`` where the AABB of sphere k overlaps box n (closed intervals).

    Two levels, all numpy: boxes around chunks of ``chunk`` consecutive spheres (consecutive samples of a
    trajectory, or spheres of one robot link, lie close together) against every obstacle box, then each sphere
    of an overlapping chunk against that obstacle box.

    Args:
        centres: (K, 3) sphere centres in metres.
        radii: (K,) sphere radii in metres.
        lo: (N, 3) box minima in metres.
        hi: (N, 3) box maxima in metres.
        chunk: spheres per chunk (>= 1).

    Returns:
        Two (P,) int64 arrays, sphere indices and box indices, grouped by chunk then box.
    """
    count = centres.shape[0]
    if count == 0 or lo.shape[0] == 0:
        return _EMPTY, _EMPTY
    chunks = -(-count // chunk)
    # Axis-first (3, K) layout keeps every reduction below on contiguous memory.
    lower = np.empty((3, chunks * chunk))
    upper = np.empty((3, chunks * chunk))
    np.subtract(centres.T, radii, out=lower[:, :count])
    np.add(centres.T, radii, out=upper[:, :count])
    lower[:, count:] = lower[:, count - 1 : count]
    upper[:, count:] = upper[:, count - 1 : count]
    chunk_lo = lower.reshape(3, chunks, chunk).min(axis=2)
    chunk_hi = upper.reshape(3, chunks, chunk).max(axis=2)
    box_lo = lo.T
    box_hi = hi.T
    overlap = (chunk_hi[0, :, None] >= box_lo[0]) & (chunk_lo[0, :, None] <= box_hi[0])
    overlap &= (chunk_hi[1, :, None] >= box_lo[1]) & (chunk_lo[1, :, None] <= box_hi[1])
    overlap &= (chunk_hi[2, :, None] >= box_lo[2]) & (chunk_lo[2, :, None] <= box_hi[2])
    cs, ns = np.nonzero(overlap)
    if cs.size == 0:
        return _EMPTY, _EMPTY
    ks = (cs[:, None] * chunk + np.arange(chunk)).ravel()
    ns = np.repeat(ns, chunk)
    pair_lo = box_lo[:, ns]
    pair_hi = box_hi[:, ns]
    sphere_lo = lower[:, ks]
    sphere_hi = upper[:, ks]
    keep = (sphere_hi[0] >= pair_lo[0]) & (sphere_lo[0] <= pair_hi[0])
    keep &= (sphere_hi[1] >= pair_lo[1]) & (sphere_lo[1] <= pair_hi[1])
    keep &= (sphere_hi[2] >= pair_lo[2]) & (sphere_lo[2] <= pair_hi[2])
    keep &= ks < count
    return ks[keep].astype(np.int64), ns[keep].astype(np.int64)


_EMPTY: IntArray = np.zeros(0, dtype=np.int64)


def boxes_overlap_box(lo: FloatArray, hi: FloatArray, los: FloatArray, his: FloatArray) -> IntArray:
    """Indices of the (N, 3) boxes ``los``-``his`` that overlap the box ``lo``-``hi`` (metres, closed)."""
    if los.shape[0] == 0:
        return np.zeros(0, dtype=np.int64)
    overlap = np.all((los <= hi) & (his >= lo), axis=1)
    return np.nonzero(overlap)[0].astype(np.int64)
