"""The compute_path_to_pose action's request handling (ros/nav2_planner_action.py); end to end: test_nav2_host.py."""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")
from geometry_msgs.msg import PoseStamped

from drd_planner.planning.nav2_codes import Nav2Error
from drd_planner.ros.nav2_planner_action import duration_of, request_poses


def _pose(frame: str, x: float = 10.0, yaw_w: float = 1.0) -> PoseStamped:
    msg = PoseStamped()
    msg.header.frame_id = frame
    msg.pose.position.x, msg.pose.position.z = x, 65.0
    msg.pose.orientation.w = yaw_w
    return msg


def test_duration_of_splits_seconds() -> None:
    d = duration_of(2.25)
    assert (d.sec, d.nanosec) == (2, 250_000_000)
    assert (duration_of(-1.0).sec, duration_of(-1.0).nanosec) == (0, 0)


def test_frames_empty_is_the_planning_frame_another_is_tf_error() -> None:
    request = SimpleNamespace(goal=_pose(""), start=_pose("odom"), use_start=False)
    parsed = request_poses(request, "map")
    assert not isinstance(parsed, Nav2Error)
    goal, start = parsed
    assert start is None
    assert goal.position is not None
    assert goal.position[0] == 10.0
    assert goal.yaw == 0.0
    request.use_start = True  # now the start's frame counts
    refused = request_poses(request, "map")
    assert isinstance(refused, Nav2Error)
    assert refused.name == "TF_ERROR"
    assert "'odom'" in refused.text


def test_a_malformed_pose_is_unknown() -> None:
    request = SimpleNamespace(goal=_pose("map", x=math.nan), start=_pose("map"), use_start=False)
    refused = request_poses(request, "map")
    assert isinstance(refused, Nav2Error)
    assert refused.name == "UNKNOWN"
