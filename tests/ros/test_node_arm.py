"""The node with the arm tree (real rclpy): goal_joints and goal_pose requests, JointTrajectory plus the
end-effector path, robot_description handling, and bad arm input."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

rclpy = pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")

from conftest import own_query  # noqa: E402
from geometry_msgs.msg import PoseStamped  # noqa: E402
from harness import Peer, active_planner, private_context, spin_until, use_domain  # noqa: E402
from rclpy.lifecycle import TransitionCallbackReturn  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402
from std_msgs.msg import String  # noqa: E402

from drd_msgs_py.factory import RclpyMessages  # noqa: E402
from drd_planner.domains.arm import ArmDomain, default_panda_dir  # noqa: E402
from drd_planner.planner import load_prior  # noqa: E402
from drd_planner.planning.map_intake import obstacle_map  # noqa: E402
from drd_planner.planning.map_state import MapSnapshot  # noqa: E402
from drd_planner.planning.session import QuerySession  # noqa: E402
from drd_planner.planning.world_messages import obstacle_markers  # noqa: E402
from drd_planner.ros.node import PlannerNode  # noqa: E402

TREE = Path(__file__).resolve().parents[2] / "trees" / "arm_table_clutter.npz"
FRAME = "panda_link0"
use_domain(90)


@pytest.fixture
def context() -> Iterator[Any]:
    with private_context() as ctx:
        yield ctx


def _node(ctx: Any) -> PlannerNode:
    return PlannerNode(
        context=ctx,
        parameter_overrides=[
            Parameter("prior_paths", value=[str(TREE)]),
            Parameter("frame_id", value=FRAME),
            Parameter("start_without_robot_state", value="prior_start"),
        ],
    )


def _world_markers(domain: ArmDomain, seed: int) -> Any:
    world = domain.make_world("table_clutter", seed)
    obstacles = [(f"object/{k}", p.shape, p.pose) for k, p in enumerate(world.obstacles)]
    return obstacle_markers(obstacles, frame_id=FRAME, msgs=RclpyMessages())


def _joint_goal(session: QuerySession, *, reverse: bool = True) -> JointState:
    msg = JointState()
    msg.header.frame_id = FRAME
    names, q = list(session.joint_names), [float(v) for v in session.goal_state]
    if reverse:  # any order of names is accepted
        names, q = names[::-1], q[::-1]
    msg.name, msg.position = names, q
    return msg


@pytest.mark.slow
def test_arm_requests_give_a_trajectory_and_the_end_effector_path(context: Any) -> None:
    node = _node(context)
    peer = Peer(context)
    with active_planner(context, node, peer) as executor:
        session = node.sessions[0]
        domain = session.domain
        assert isinstance(domain, ArmDomain)
        assert session.domain.plans_joint_goals
        markers = _world_markers(domain, 5)
        peer.obstacles.publish(markers)
        assert spin_until(executor, lambda: node.snapshot.version >= 1)
        peer.joint_goals.publish(_joint_goal(session))
        assert spin_until(executor, lambda: bool(peer.trajectories) and bool(peer.plans) and bool(peer.checks))
        trajectory, path, log = peer.trajectories[-1], peer.plans[-1], peer.checks[-1]
        assert list(trajectory.joint_names) == list(session.joint_names)
        q = np.array([p.positions for p in trajectory.points])
        np.testing.assert_allclose(q[0], session.vertex_state(domain.start))
        np.testing.assert_allclose(q[-1], session.goal_state)
        assert np.max(np.abs(np.diff(q, axis=0))) <= domain.resolution + 1e-9  # finely sampled
        times = [p.time_from_start.sec + p.time_from_start.nanosec * 1e-9 for p in trajectory.points]
        assert np.all(np.diff(times) > 0)
        # The end-effector path follows the trajectory by forward kinematics.
        assert path.header.frame_id == FRAME
        assert len(path.poses) == len(trajectory.points)
        xyz = np.array([[p.pose.position.x, p.pose.position.y, p.pose.position.z] for p in path.poses])
        np.testing.assert_allclose(xyz, domain.end_effector_positions(q), atol=1e-9)
        # Same checks as the offline session on the same decoded map; the plan's edges were checked free.
        snapshot = MapSnapshot(1, obstacle_map(markers, frame_id=FRAME), None, session.margin)
        offline_session = QuerySession(load_prior(TREE), name="offline")
        offline = offline_session.plan(snapshot, *own_query(offline_session), seed=0)
        assert offline.ok
        assert [s.name for s in log.status] == [f"edge/{c.edge}" for c in offline.checks]
        assert [s.level == b"\x00" for s in log.status] == [c.free for c in offline.checks]
        np.testing.assert_allclose(q, offline.states)
        # An end-effector goal position on goal_pose reaches the same tree.
        goal = PoseStamped()
        goal.header.frame_id = FRAME
        goal.pose.position.x, goal.pose.position.y, goal.pose.position.z = (float(v) for v in session.goal_position)
        count = len(peer.trajectories)
        peer.goals.publish(goal)
        assert spin_until(executor, lambda: len(peer.trajectories) > count)
        np.testing.assert_allclose([p.positions for p in peer.trajectories[-1].points], q)


def test_robot_description_is_used_and_bad_ones_are_refused(context: Any) -> None:
    node = _node(context)
    try:
        assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS
        session = node.sessions[0]
        domain = session.domain
        assert isinstance(domain, ArmDomain)
        # The robot stack's description has mesh collisions: kinematics from it, spheres from the tree's model.
        urdf = (default_panda_dir() / "panda.urdf").read_text(encoding="utf-8")
        node._on_map("robot_description", String(data=urdf))
        robot = node.snapshot.robot
        assert robot is not None
        assert node.snapshot.version == 1
        assert robot.chain.joint_names == domain.robot.chain.joint_names
        assert robot.spheres.count == domain.robot.spheres.count
        # Plans then check with that model (self-collision included): still the offline answer.
        node._on_map("obstacles", _world_markers(domain, 5))
        assert node.plan_for(_pose_goal(session)) is not None
        # A longer forearm: different kinematics, so a different end-effector goal position.
        stretched = urdf.replace(
            '<origin rpy="1.57079632679 0 0" xyz="0 -0.316 0"/>',
            '<origin rpy="1.57079632679 0 0" xyz="0 -0.45 0"/>',
        )
        assert stretched != urdf
        node._on_map("robot_description", String(data=stretched))
        assert node.snapshot.robot is not None
        assert node.snapshot.robot is not robot
        moved = session.positions(session.goal_state, node.snapshot)[0]
        assert np.linalg.norm(moved - session.goal_position) > 0.05
        # Refused: not XML, and a robot with other joints; the model stays as it was.
        version = node.snapshot.version
        for bad, words in [
            ("not xml", "robot_description refused"),
            (_renamed_joint(urdf), "tree was built for"),
        ]:
            node._on_map("robot_description", String(data=bad))
            assert words in node.errors[-1]
            assert node.snapshot.version == version
    finally:
        node.destroy_node()


def _pose_goal(session: QuerySession) -> PoseStamped:
    goal = PoseStamped()
    goal.header.frame_id = FRAME
    goal.pose.position.x, goal.pose.position.y, goal.pose.position.z = (float(v) for v in session.goal_position)
    return goal


def _renamed_joint(urdf: str) -> str:
    return urdf.replace('"panda_joint4"', '"elbow"')


def test_bad_joint_goals_are_refused(context: Any) -> None:
    node = _node(context)
    try:
        assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS
        session = node.sessions[0]
        cases: list[tuple[JointState, str]] = []
        missing = _joint_goal(session)
        missing.name, missing.position = list(missing.name)[1:], list(missing.position)[1:]
        cases.append((missing, "missing joints"))
        nan = _joint_goal(session)
        nan.position = [float("nan")] * len(nan.position)
        cases.append((nan, "finite"))
        ragged = _joint_goal(session)
        ragged.position = list(ragged.position)[:3]
        cases.append((ragged, "positions"))
        for msg, words in cases:
            node._on_request("goal_joints", msg)
            assert words in node.errors[-1], node.errors[-1]
        # A valid goal before any obstacle map: refused, nothing planned.
        node._on_request("goal_joints", _joint_goal(session))
        node._serve()
        assert "no maps" in node.errors[-1]
        assert node.published is None
    finally:
        node.destroy_node()
