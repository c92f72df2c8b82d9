"""Requests as the node reads them: goal snapping, robot states from messages, which prior serves a request."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")

from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState

from drd_msgs_py.exceptions import MessageError
from drd_planner.exceptions import PlanningError
from drd_planner.planner import load_prior
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.requests import (
    Goal,
    GoalTolerances,
    ambiguity,
    goal_endpoint,
    goal_from_pose,
    joint_vector,
    pick_session,
    read_goal,
    read_robot_state,
    start_from_odometry,
)
from drd_planner.planning.session import QuerySession

TREE = Path(__file__).resolve().parents[2] / "trees" / "heli_wires.npz"


@pytest.fixture(scope="module")
def session() -> QuerySession:
    return QuerySession(load_prior(TREE), name="heli_wires")


def _goal(position: np.ndarray, yaw: float = 0.0) -> Goal:
    return Goal(position=np.asarray(position, dtype=float), yaw=yaw)


def test_a_goal_near_the_stored_goal_is_that_vertex(session: QuerySession) -> None:
    stored = int(session.domain.goal)
    near = session.vertex_state(stored)[:3] + np.array([0.5, -0.5, 0.3])
    assert goal_endpoint(session, _goal(near), MapSnapshot(0)) == stored


def test_a_goal_near_another_vertex_is_that_vertex(session: QuerySession) -> None:
    states = session.prior.graph.vertex_states
    assert states is not None
    stored = int(session.domain.goal)
    vertex = int(np.flatnonzero(np.max(np.abs(states[:, :3] - states[stored, :3]), axis=1) > 50)[0])
    near = states[vertex, :3] + np.array([0.4, 0.0, -0.4])
    got = goal_endpoint(session, _goal(near, yaw=float(states[vertex, 3])), MapSnapshot(0))
    assert got == vertex


def test_a_goal_far_from_every_vertex_is_its_own_state(session: QuerySession) -> None:
    states = session.prior.graph.vertex_states
    assert states is not None
    position = states[:, :3].mean(axis=0) + np.array([1234.5, 0.0, 0.0])
    got = goal_endpoint(session, _goal(position, yaw=0.25), MapSnapshot(0))
    assert isinstance(got, np.ndarray)
    np.testing.assert_allclose(got, [*position, 0.25])


def test_a_goal_yaw_is_honoured_and_a_goal_without_orientation_takes_any_heading(
    session: QuerySession,
) -> None:
    stored = int(session.domain.goal)
    position = session.vertex_state(stored)[:3]
    # the stored goal flies in at heading 0: a goal asking pi/2 there is its own state, yaw kept
    turned = goal_endpoint(session, _goal(position, yaw=math.pi / 2), MapSnapshot(0))
    assert isinstance(turned, np.ndarray)
    np.testing.assert_allclose(turned, [*position, math.pi / 2])
    assert goal_endpoint(session, _goal(position, yaw=0.05), MapSnapshot(0)) == stored  # within 0.1 rad
    strict = GoalTolerances(yaw_rad=0.01)
    assert isinstance(goal_endpoint(session, _goal(position, yaw=0.05), MapSnapshot(0), strict), np.ndarray)
    assert goal_endpoint(session, Goal(position=position, yaw=None), MapSnapshot(0)) == stored
    off = goal_endpoint(session, Goal(position=position + np.array([0.0, 37.0, 0.0]), yaw=None), MapSnapshot(0))
    assert isinstance(off, np.ndarray)
    assert np.isnan(off[3])
    assert np.allclose(off[:3], position + np.array([0.0, 37.0, 0.0]))
    pose = PoseStamped()
    pose.header.frame_id = "map"
    pose.pose.position.x, pose.pose.position.y = 10.0, 20.0
    pose.pose.orientation.w = 0.0  # ROS 2's default is the identity (yaw 0); all four zero: no yaw
    free = goal_from_pose(pose, "map")
    assert free.yaw is None
    assert "any yaw" in free.describe()
    pose.pose.orientation.z = 0.5  # not a unit quaternion: still refused
    with pytest.raises(MessageError, match="unit quaternion"):
        goal_from_pose(pose, "map")


def test_poses_and_odometry_in_the_wrong_frame_or_with_nan_are_refused() -> None:
    pose = PoseStamped()
    pose.header.frame_id = "odom"
    with pytest.raises(MessageError, match="frame 'odom'"):
        goal_from_pose(pose, "map")
    odom = Odometry()
    odom.header.frame_id = "map"
    odom.pose.pose.position.x = math.nan
    with pytest.raises(MessageError, match="finite"):
        start_from_odometry(odom, "map")
    odom.pose.pose.position.x = 3.0
    odom.pose.pose.orientation.z, odom.pose.pose.orientation.w = math.sin(0.3), math.cos(0.3)  # yaw 0.6
    np.testing.assert_allclose(start_from_odometry(odom, "map"), [3.0, 0.0, 0.0, 0.6])


def test_joint_states_keep_the_prior_joints_in_order_and_refuse_bad_ones() -> None:
    msg = JointState()
    msg.name = ["finger", "j2", "j1"]
    msg.position = [0.04, 2.0, 1.0]
    np.testing.assert_allclose(joint_vector(msg, ("j1", "j2")), [1.0, 2.0])
    msg.name = ["j1", "j1", "j2"]
    with pytest.raises(MessageError, match="repeat"):
        joint_vector(msg, ("j1", "j2"))
    msg.name = ["j1", "finger", "x"]
    with pytest.raises(MessageError, match="missing joints"):
        joint_vector(msg, ("j1", "j2"))


def test_one_prior_per_domain_serves_requests(session: QuerySession) -> None:
    twin = QuerySession(load_prior(TREE), name="again")
    assert ambiguity([session]) is None
    reason = ambiguity([session, twin])
    assert reason is not None
    assert "helicopter" in reason
    assert "'again'" in reason
    assert pick_session([session], _goal(np.zeros(3))) is session
    assert pick_session([session], Goal(joints=np.zeros(7))) is None  # joints need an arm prior


def test_one_parser_reads_goals_and_robot_states_of_any_namespace(session: QuerySession) -> None:
    pose = PoseStamped()
    pose.header.frame_id = "map"
    pose.pose.position.x, pose.pose.orientation.w = 5.0, 1.0
    goal = read_goal("/robot1/goal_pose", pose, [session], "map")
    assert goal.joints is None
    assert goal.position is not None
    assert goal.position[0] == 5.0
    with pytest.raises(PlanningError, match="no prior that plans joint-space goals"):
        read_goal("goal_joints", JointState(), [session], "map")
    odom = Odometry()
    odom.header.frame_id = "map"
    odom.pose.pose.orientation.w = 1.0
    read = read_robot_state("odom", odom, [session], "map")
    assert read is not None
    assert read[0] == "odom"
    assert read[1].shape == (4,)
    assert read_robot_state("/robot1/joint_states", JointState(), [session], "map") is None  # not ours
