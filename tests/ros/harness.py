"""Shared pieces of the real-rclpy node tests: a private context, a peer node, spinning until done."""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Path as PathMsg
from rclpy.executors import SingleThreadedExecutor
from rclpy.lifecycle import TransitionCallbackReturn
from sensor_msgs.msg import JointState, PointCloud2
from std_msgs.msg import String
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import MarkerArray

from drd_msgs_py.factory import RclpyMessages
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Box
from drd_planner.planning.world_messages import obstacle_markers
from drd_planner.ros.node import LATCHED


def use_domain(base: int) -> None:
    """Keep DDS traffic on this machine, on a domain id of its own per test process."""
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    os.environ["ROS_DOMAIN_ID"] = str(base + os.getpid() % 20)


@contextmanager
def private_context() -> Iterator[Any]:
    """A fresh rclpy context, shut down afterwards."""
    ctx = rclpy.context.Context()
    rclpy.init(context=ctx)
    try:
        yield ctx
    finally:
        ctx.try_shutdown()


class Peer:
    """Publishes maps and requests; records everything the planner publishes."""

    def __init__(self, ctx: Any) -> None:
        self.node = rclpy.create_node("peer", context=ctx)
        self.obstacles = self.node.create_publisher(MarkerArray, "obstacles", LATCHED)
        self.terrain = self.node.create_publisher(PointCloud2, "terrain", LATCHED)
        self.robot_description = self.node.create_publisher(String, "robot_description", LATCHED)
        self.goals = self.node.create_publisher(PoseStamped, "goal_pose", 10)
        self.joint_goals = self.node.create_publisher(JointState, "goal_joints", 10)
        self.plans: list[PathMsg] = []
        self.trajectories: list[JointTrajectory] = []
        self.checks: list[DiagnosticArray] = []
        self.diagnostics: list[DiagnosticArray] = []
        self.node.create_subscription(PathMsg, "plan", self.plans.append, LATCHED)
        self.node.create_subscription(JointTrajectory, "joint_trajectory", self.trajectories.append, LATCHED)
        self.node.create_subscription(DiagnosticArray, "edge_checks", self.checks.append, 10)
        self.node.create_subscription(DiagnosticArray, "/diagnostics", self.diagnostics.append, 10)

    def block_edge(self, session: Any, edge: int, name: str = "extra/1") -> None:
        """Add a 30 m box at the middle of a helicopter edge's states to the latched obstacle map."""
        states = session.edge_states(edge)
        middle = Pose(position=tuple(float(v) for v in states[len(states) // 2, :3]))
        markers = [(name, Box((30.0, 30.0, 30.0)), middle)]
        msg = obstacle_markers(markers, frame_id="map", msgs=RclpyMessages(), delete_all_first=False)
        self.obstacles.publish(msg)

    def summaries(self, name: str = "drd_planner: plan") -> list[dict[str, str]]:
        """The key/values of every received summary status called ``name`` (level under ``level``)."""
        out = []
        for array in self.diagnostics:
            for status in array.status:
                if status.name == name and status.values:
                    values = {kv.key: kv.value for kv in status.values}
                    values["level"] = str(ord(status.level) if isinstance(status.level, bytes) else status.level)
                    values["message"] = status.message
                    out.append(values)
        return out


@contextmanager
def active_planner(ctx: Any, node: Any, peer: Peer) -> Iterator[Any]:
    """Configure and activate ``node``; yield an executor spinning it and ``peer``; destroy both after."""
    executor = SingleThreadedExecutor(context=ctx)
    executor.add_node(node)
    executor.add_node(peer.node)
    try:
        assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS, node.errors
        assert node.trigger_activate() == TransitionCallbackReturn.SUCCESS
        yield executor
    finally:
        executor.shutdown()
        node.destroy_node()
        peer.node.destroy_node()


def spin_until(executor: Any, done: Callable[[], bool], timeout: float = 30.0) -> bool:
    """Spin ``executor`` until ``done()`` or ``timeout`` seconds; whether it got done."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        executor.spin_once(timeout_sec=0.05)
        if done():
            return True
    return False


def spin_for(executor: Any, seconds: float) -> None:
    """Spin ``executor`` for ``seconds`` (lets late messages arrive)."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        executor.spin_once(timeout_sec=0.02)
