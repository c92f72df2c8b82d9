"""The is_path_valid service's reading of a Path (ros/nav2_path_validity.py); end to end: test_nav2_host.py."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Path as PathMsg

from drd_planner.ros.nav2_path_validity import path_arrays


def test_path_arrays_reads_positions_and_yaws() -> None:
    path = PathMsg()
    for k, yaw in enumerate((0.0, math.pi / 2)):
        stamped = PoseStamped()
        stamped.pose.position.x, stamped.pose.position.y, stamped.pose.position.z = float(k), 2.0, 65.0
        stamped.pose.orientation.z, stamped.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
        path.poses.append(stamped)
    path.poses.append(PoseStamped())  # the zero quaternion: no orientation, yaw 0
    positions, yaws = path_arrays(path)
    assert positions.tolist() == [[0.0, 2.0, 65.0], [1.0, 2.0, 65.0], [0.0, 0.0, 0.0]]
    assert np.allclose(yaws, [0.0, math.pi / 2, 0.0])
    empty_positions, empty_yaws = path_arrays(PathMsg())
    assert empty_positions.shape == (0, 3)
    assert empty_yaws.shape == (0,)
