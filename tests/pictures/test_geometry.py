"""What a plan picture draws, in world coordinates: outlines, hulls, edge polylines, wire crossings."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Box, Capsule, Cylinder, Sphere, TriangleMesh
from drd_planner.pictures.geometry import (
    TOP,
    capsule_segment,
    convex_hull,
    profile_crossings,
    shape_outline,
)


def test_convex_hull_is_counter_clockwise_from_the_lowest_vertex() -> None:
    square = np.array([[1.0, 1.0], [0.0, 0.0], [0.5, 0.5], [1.0, 0.0], [0.0, 1.0], [0.5, 0.0]])
    assert convex_hull(square).tolist() == [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
    line = np.array([[2.0, 2.0], [0.0, 0.0], [1.0, 1.0], [3.0, 3.0]])
    assert convex_hull(line).tolist() == [[0.0, 0.0], [3.0, 3.0]]  # collinear: the two ends
    assert convex_hull(np.array([[1.0, 2.0], [1.0, 2.0 + 1e-12]])).tolist() == [[1.0, 2.0]]
    assert TOP.shape == (3, 2)


def test_outlines_of_posed_shapes() -> None:
    yaw = math.radians(30.0)
    box = shape_outline(Box((4.0, 2.0, 10.0)), Pose((1.0, 2.0, 0.0), (0, 0, math.sin(yaw / 2), math.cos(yaw / 2))))
    assert box.shape == (4, 2)
    area = 0.5 * abs(np.dot(box[:, 0], np.roll(box[:, 1], 1)) - np.dot(box[:, 1], np.roll(box[:, 0], 1)))
    assert area == pytest.approx(8.0)
    assert box.mean(axis=0) == pytest.approx([1.0, 2.0])
    circle = shape_outline(Cylinder(3.0, 50.0), Pose((10.0, 0.0, 25.0)))
    assert np.linalg.norm(circle - [10.0, 0.0], axis=1) == pytest.approx(np.full(len(circle), 3.0))
    # A cylinder lying along x, seen from the side (x, z): a 20 x 6 rectangle.
    lying = Pose((0.0, 0.0, 5.0), (0.0, math.sin(math.pi / 4), 0.0, math.cos(math.pi / 4)))
    side = shape_outline(Cylinder(3.0, 20.0), lying, plane=[[1, 0], [0, 0], [0, 1]])
    assert np.ptp(side, axis=0) == pytest.approx([20.0, 6.0])
    sphere = shape_outline(Sphere(0.5), Pose((0.0, 1.0, 2.0)), plane=[[0, 0], [1, 0], [0, 1]])
    assert np.linalg.norm(sphere - [1.0, 2.0], axis=1) == pytest.approx(np.full(len(sphere), 0.5))
    capsule = shape_outline(Capsule(1.0, 4.0), Pose())  # along z, seen from above: a unit disc
    assert np.ptp(capsule, axis=0) == pytest.approx([2.0, 2.0], abs=1e-2)
    flat = TriangleMesh([[0, 0, 0], [1, 0, 0], [0, 0, 1]], [[0, 1, 2]])  # in the x-z plane
    assert shape_outline(flat, Pose()).shape == (2, 2)  # edge-on from above: a segment


def test_capsule_segment_and_crossings() -> None:
    tilt = Pose((5.0, 0.0, 4.0), (math.sin(math.pi / 4), 0.0, 0.0, math.cos(math.pi / 4)))  # z axis -> -y
    ends = capsule_segment(Capsule(0.1, 2.0), tilt)
    assert np.sort(ends[:, 1]) == pytest.approx([-1.0, 1.0])
    assert ends[:, [0, 2]] == pytest.approx(np.array([[5.0, 4.0], [5.0, 4.0]]))
    reference = np.array([[0.0, 0.0, 50.0], [10.0, 0.0, 50.0], [10.0, 10.0, 50.0]])
    wires = np.array(
        [
            [[5.0, -1.0, 3.0], [5.0, 1.0, 5.0]],  # crosses the first leg at s = 5, z = 4
            [[9.0, 4.0, 7.0], [11.0, 4.0, 9.0]],  # crosses the second leg at s = 14, z = 8
            [[20.0, -5.0, 1.0], [20.0, 5.0, 1.0]],  # misses
        ]
    )
    s, z = profile_crossings(reference, wires)
    assert s == pytest.approx([5.0, 14.0])
    assert z == pytest.approx([4.0, 8.0])
    assert profile_crossings(reference, np.zeros((0, 2, 3)))[0].size == 0
