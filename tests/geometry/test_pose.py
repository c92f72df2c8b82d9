"""Pose: validation, ROS (x, y, z, w) quaternion order, matrices and the FCL transform."""

from __future__ import annotations

import math

import fcl
import numpy as np
import pytest

from drd_planner.exceptions import GeometryError
from drd_planner.geometry.pose import Pose

YAW_90 = (0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4))  # ROS order: x, y, z, w


def test_identity_and_defaults() -> None:
    pose = Pose.identity()
    np.testing.assert_array_equal(pose.position, [0, 0, 0])
    np.testing.assert_array_equal(pose.quaternion_xyzw, [0, 0, 0, 1])
    np.testing.assert_allclose(pose.matrix(), np.eye(4))


def test_quaternion_is_normalised_and_read_only() -> None:
    pose = Pose((1, 2, 3), (0, 0, 0, 2))
    np.testing.assert_allclose(pose.quaternion_xyzw, [0, 0, 0, 1])
    with pytest.raises(ValueError, match="read-only"):
        pose.position[0] = 5.0


def test_yaw_90_rotates_x_onto_y() -> None:
    pose = Pose((1.0, 0.0, 0.0), YAW_90)
    np.testing.assert_allclose(pose.rotation() @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(pose.transform_points([[2.0, 0.0, 0.0]]), [[1.0, 2.0, 0.0]], atol=1e-12)


def test_to_fcl_reorders_quaternion_to_wxyz() -> None:
    pose = Pose((1.0, 2.0, 3.0), YAW_90)
    transform = pose.to_fcl()
    np.testing.assert_allclose(transform.getRotation(), pose.rotation(), atol=1e-12)
    np.testing.assert_allclose(transform.getTranslation(), [1, 2, 3])
    np.testing.assert_allclose(transform.getQuatRotation(), [YAW_90[3], 0, 0, YAW_90[2]], atol=1e-12)


def test_fcl_itself_reads_wxyz() -> None:
    """The trap: handing FCL the ROS (x, y, z, w) array gives another rotation."""
    wrong = fcl.Transform(np.array(YAW_90), np.zeros(3))
    assert not np.allclose(wrong.getRotation() @ [1, 0, 0], [0, 1, 0])


def test_matrix_round_trip_and_compose_inverse() -> None:
    pose = Pose((0.5, -1.0, 2.0), (0.1, -0.3, 0.5, 0.8))
    again = Pose.from_matrix(pose.matrix())
    np.testing.assert_allclose(again.matrix(), pose.matrix(), atol=1e-12)
    np.testing.assert_allclose(pose.compose(pose.inverse()).matrix(), np.eye(4), atol=1e-12)
    shifted = Pose((1, 0, 0)).compose(Pose((0, 2, 0), YAW_90))
    np.testing.assert_allclose(shifted.position, [1, 2, 0])


def test_equality_and_hash() -> None:
    assert Pose((1, 2, 3)) == Pose([1.0, 2.0, 3.0])
    assert hash(Pose((1, 2, 3))) == hash(Pose((1.0, 2.0, 3.0)))
    assert Pose((1, 2, 3)) != Pose((1, 2, 4))


@pytest.mark.parametrize(
    ("position", "quaternion", "message"),
    [
        ((0, 0), (0, 0, 0, 1), "position"),
        ((0, 0, math.nan), (0, 0, 0, 1), "finite"),
        ((0, 0, 0), (0, 0, 0, 0), "non-zero"),
        ((0, 0, 0), (0, 0, 1), "quaternion"),
        (("a", 0, 0), (0, 0, 0, 1), "numeric"),
    ],
)
def test_invalid_pose_raises(position: object, quaternion: object, message: str) -> None:
    with pytest.raises(GeometryError, match=message):
        Pose(position, quaternion)  # type: ignore[arg-type]


def test_from_matrix_rejects_non_rotations() -> None:
    bad = np.eye(4)
    bad[0, 0] = 2.0
    with pytest.raises(GeometryError, match="orthonormal"):
        Pose.from_matrix(bad)
    mirror = np.diag([1.0, 1.0, -1.0, 1.0])
    with pytest.raises(GeometryError, match="determinant"):
        Pose.from_matrix(mirror)
    with pytest.raises(GeometryError, match="last row"):
        Pose.from_matrix(np.ones((4, 4)))
