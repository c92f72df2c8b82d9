"""The plain data of map messages: value equality where it is meaningful, grids and their shape."""

from __future__ import annotations

import numpy as np

from drd_msgs_py.shapes import BoxData, CylinderData, HeightGrid, LineStripData, PoseData, SphereData


def test_small_shapes_and_poses_compare_by_value() -> None:
    assert PoseData() == PoseData((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
    assert BoxData((1.0, 2.0, 3.0)) == BoxData((1.0, 2.0, 3.0)) != BoxData((1.0, 2.0, 4.0))
    assert SphereData(1.0) != CylinderData(1.0, 1.0)
    strip = LineStripData(np.zeros((2, 3)), 0.1)
    assert strip != LineStripData(np.zeros((2, 3)), 0.1)  # arrays inside: equal only to itself


def test_a_height_grid_knows_its_shape() -> None:
    grid = HeightGrid((1.0, 2.0), 0.5, np.zeros((3, 4)))
    assert grid.shape == (3, 4)
    assert grid.origin == (1.0, 2.0)
