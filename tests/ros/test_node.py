"""The lifecycle node with real rclpy: transitions, maps -> plan, the service, and bad input."""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

rclpy = pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")

from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
from geometry_msgs.msg import PoseStamped  # noqa: E402
from lifecycle_msgs.msg import State  # noqa: E402
from nav_msgs.msg import Path as PathMsg  # noqa: E402
from nav_msgs.srv import GetPlan  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.lifecycle import TransitionCallbackReturn  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from sensor_msgs.msg import PointCloud2  # noqa: E402
from visualization_msgs.msg import MarkerArray  # noqa: E402

from drd_msgs_py.factory import RclpyMessages  # noqa: E402
from drd_msgs_py.obstacles import obstacle_update  # noqa: E402
from drd_msgs_py.terrain import heightfield_from_cloud  # noqa: E402
from drd_msgs_py.worlds import helicopter_world_messages  # noqa: E402
from drd_planner.data.tree_file import load_tree  # noqa: E402
from drd_planner.domains.helicopter import HelicopterDomain  # noqa: E402
from drd_planner.planning.map_state import MapSnapshot  # noqa: E402
from drd_planner.planning.session import PlanningSession  # noqa: E402
from drd_planner.ros.node import LATCHED, PlannerNode  # noqa: E402

TREE = Path(__file__).resolve().parents[2] / "trees" / "heli_wires.npz"
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
os.environ["ROS_DOMAIN_ID"] = str(60 + os.getpid() % 40)


@pytest.fixture
def context() -> Iterator[Any]:
    ctx = rclpy.context.Context()
    rclpy.init(context=ctx)
    yield ctx
    ctx.try_shutdown()


def _node(ctx: Any, trees: list[str]) -> PlannerNode:
    return PlannerNode(context=ctx, parameter_overrides=[Parameter("tree_paths", value=trees)])


class _Peer:
    """Publishes maps and requests, records what the planner publishes."""

    def __init__(self, ctx: Any) -> None:
        self.node = rclpy.create_node("peer", context=ctx)
        self.obstacles = self.node.create_publisher(MarkerArray, "obstacles", LATCHED)
        self.terrain = self.node.create_publisher(PointCloud2, "terrain", LATCHED)
        self.goals = self.node.create_publisher(PoseStamped, "goal_pose", 10)
        self.plans: list[PathMsg] = []
        self.checks: list[DiagnosticArray] = []
        self.diagnostics: list[DiagnosticArray] = []
        self.node.create_subscription(PathMsg, "plan", self.plans.append, LATCHED)
        self.node.create_subscription(DiagnosticArray, "edge_checks", self.checks.append, 10)
        self.node.create_subscription(DiagnosticArray, "/diagnostics", self.diagnostics.append, 10)


def _spin_until(executor: Any, done: Callable[[], bool], timeout: float = 20.0) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        executor.spin_once(timeout_sec=0.05)
        if done():
            return True
    return False


def _goal(session: PlanningSession, frame: str = "map") -> PoseStamped:
    goal = PoseStamped()
    goal.header.frame_id = frame
    x, y, z = (float(v) for v in session.goal_state[:3])
    goal.pose.position.x, goal.pose.position.y, goal.pose.position.z = x, y, z
    return goal


def test_lifecycle_maps_request_plan_and_service(context: Any) -> None:
    node = _node(context, [str(TREE)])
    peer = _Peer(context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    executor.add_node(peer.node)
    try:
        assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS
        assert node.trigger_activate() == TransitionCallbackReturn.SUCCESS
        session = node.sessions[0]
        domain = session.domain
        assert isinstance(domain, HelicopterDomain)
        markers, cloud = helicopter_world_messages(
            domain.make_world("wires", 3), wire_segments=8, frame_id="map", msgs=RclpyMessages()
        )
        # A request before the maps: a clear error and no plan.
        peer.goals.publish(_goal(session))
        assert _spin_until(executor, lambda: any("no maps" in e for e in node.errors))
        assert not peer.plans
        peer.terrain.publish(cloud)
        peer.obstacles.publish(markers)
        assert _spin_until(executor, lambda: node.snapshot.version >= 2)
        peer.goals.publish(_goal(session))
        assert _spin_until(executor, lambda: bool(peer.plans) and bool(peer.checks))
        plan, log = peer.plans[-1], peer.checks[-1]
        assert plan.header.frame_id == "map" and len(plan.poses) > 2
        last = plan.poses[-1].pose.position
        assert np.allclose([last.x, last.y, last.z], session.goal_state[:3])
        # Every edge of the plan was checked free, and the log equals the offline session on the same maps.
        update = obstacle_update(markers, frame_id="map")
        snapshot = MapSnapshot(
            1,
            {k: o.parts for k, o in update.apply({}).items()},
            heightfield_from_cloud(cloud, frame_id="map"),
            session.margin,
        )
        offline = PlanningSession(load_tree(TREE), name="offline").plan(snapshot, seed=0)
        assert offline.ok
        assert [s.name for s in log.status] == [f"edge/{c.edge}" for c in offline.checks]
        assert [s.level == b"\x00" for s in log.status] == [c.free for c in offline.checks]
        free = {int(s.name.split("/")[1]) for s in log.status if s.level == b"\x00"}
        assert set(offline.path_edges) <= free
        np.testing.assert_allclose(
            [[p.pose.position.x, p.pose.position.y, p.pose.position.z] for p in plan.poses],
            offline.states[:, :3],
        )
        # The service gives the same path.
        client = peer.node.create_client(GetPlan, "get_plan")
        assert client.wait_for_service(timeout_sec=5.0)
        request = GetPlan.Request()
        request.goal = _goal(session)
        future = client.call_async(request)
        assert _spin_until(executor, future.done)
        assert len(future.result().plan.poses) == len(plan.poses)
        assert node.trigger_deactivate() == TransitionCallbackReturn.SUCCESS
        assert node.trigger_cleanup() == TransitionCallbackReturn.SUCCESS
    finally:
        executor.shutdown()
        node.destroy_node()
        peer.node.destroy_node()


def test_bad_tree_file_fails_configure_and_the_node_stays_up(context: Any, tmp_path: Path) -> None:
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a tree")
    node = _node(context, [str(bad)])
    try:
        assert node.trigger_configure() == TransitionCallbackReturn.FAILURE
        assert any("not a readable tree file" in e for e in node.errors)
        assert node._state_machine.current_state[1] == "unconfigured"
        node.set_parameters([Parameter("tree_paths", value=[str(TREE)])])
        assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS
    finally:
        node.destroy_node()


def test_bad_requests_and_maps_leave_errors_not_plans(context: Any) -> None:
    node = _node(context, [str(TREE)])
    try:
        assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS
        session = node.sessions[0]
        wrong_frame = _goal(session, frame="odom")
        assert node.plan_for(wrong_frame) is None and "frame 'odom'" in node.errors[-1]
        far = _goal(session)
        far.pose.position.x += 500.0
        assert node.plan_for(far) is None and "matches no loaded tree" in node.errors[-1]
        nan = _goal(session)
        nan.pose.position.z = float("nan")
        assert node.plan_for(nan) is None and "finite" in node.errors[-1]
        cloud = PointCloud2()
        cloud.header.frame_id = "map"
        node._on_terrain(cloud)
        assert "terrain refused" in node.errors[-1] and node.snapshot.version == 0
        assert State.PRIMARY_STATE_INACTIVE == node._state_machine.current_state[0]
    finally:
        node.destroy_node()
