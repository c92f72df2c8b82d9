"""What the node says about itself on /diagnostics: named statuses, accepted maps, a 1 Hz heartbeat."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

rclpy = pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")

from geometry_msgs.msg import PoseStamped  # noqa: E402
from harness import Peer, active_planner, private_context, spin_for, spin_until, use_domain  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from sensor_msgs.msg import PointCloud2  # noqa: E402

from drd_msgs_py.factory import RclpyMessages  # noqa: E402
from drd_planner.domains.helicopter import HelicopterDomain  # noqa: E402
from drd_planner.planning.world_messages import helicopter_world_messages  # noqa: E402
from drd_planner.ros.node import PlannerNode  # noqa: E402

TREE = Path(__file__).resolve().parents[2] / "trees" / "heli_wires.npz"
use_domain(80)


@pytest.fixture
def context() -> Iterator[Any]:
    with private_context() as ctx:
        yield ctx


def test_statuses_are_named_after_the_node_and_say_what_happened(context: Any) -> None:
    node = PlannerNode(
        context=context,
        node_name="heli_planner",
        parameter_overrides=[
            Parameter("prior_paths", value=[str(TREE)]),
            Parameter("start_without_robot_state", value="prior_start"),
        ],
    )
    peer = Peer(context)
    with active_planner(context, node, peer) as executor:
        assert spin_until(executor, lambda: bool(peer.summaries("heli_planner: heartbeat")), timeout=3.0)
        beat = peer.summaries("heli_planner: heartbeat")[-1]
        assert beat["state"] == "active"
        assert beat["maps_known"] == "False"
        assert beat["last_plan"] == "none"
        assert beat["priors"] == "1"
        assert beat["trees"] == "1"  # the deprecated key, kept for one release
        bad = PointCloud2()
        bad.header.frame_id = "map"
        peer.terrain.publish(bad)  # a map error is filed under maps, not plans
        assert spin_until(executor, lambda: any("terrain refused" in e for e in node.errors))
        spin_for(executor, 0.2)
        errors = [s for a in peer.diagnostics for s in a.status if s.level == b"\x02"]
        assert [s.name for s in errors] == ["heli_planner: maps"]
        session = node.sessions[0]
        domain = session.domain
        assert isinstance(domain, HelicopterDomain)
        markers, cloud = helicopter_world_messages(
            domain.make_world("wires", 3), wire_segments=8, frame_id="map", msgs=RclpyMessages()
        )
        peer.terrain.publish(cloud)
        peer.obstacles.publish(markers)
        assert spin_until(executor, lambda: len(peer.summaries("heli_planner: maps")) >= 2)
        maps = peer.summaries("heli_planner: maps")
        assert {m["source"] for m in maps} == {"terrain", "obstacles"}
        rows, cols = node.snapshot.terrain.shape  # type: ignore[union-attr]
        assert any(m["terrain"].startswith(f"{rows} x {cols} cells") for m in maps)
        assert maps[-1]["map_version"] == "2"
        assert int(maps[-1]["obstacles"]) > 0
        goal = PoseStamped()
        goal.header.frame_id = "map"
        goal.pose.position.x, goal.pose.position.y, goal.pose.position.z = (float(v) for v in session.goal_state[:3])
        peer.goals.publish(goal)
        assert spin_until(executor, lambda: bool(peer.summaries("heli_planner: plan")))
        plan = peer.summaries("heli_planner: plan")[-1]
        assert float(plan["planning_time"]) > 0
        assert int(plan["checks"]) == int(plan["free"]) + int(plan["blocked"])
        count = len(peer.summaries("heli_planner: heartbeat"))
        assert spin_until(executor, lambda: len(peer.summaries("heli_planner: heartbeat")) >= count + 2, timeout=3.5)
        beat = peer.summaries("heli_planner: heartbeat")[-1]
        assert beat["maps_known"] == "True"
        assert beat["plan_published"] == "True"
        assert beat["last_plan"] == "found (goal_pose)"
        assert float(beat["last_plan_age_s"]) < 5


def test_outputs_are_silent_until_activate(context: Any) -> None:
    """Lifecycle publishers: a plan made while inactive (the service is called directly) is not published."""
    node = PlannerNode(
        context=context,
        parameter_overrides=[
            Parameter("prior_paths", value=[str(TREE)]),
            Parameter("start_without_robot_state", value="prior_start"),
        ],
    )
    peer = Peer(context)
    with active_planner(context, node, peer) as executor:
        session = node.sessions[0]
        domain = session.domain
        assert isinstance(domain, HelicopterDomain)
        markers, cloud = helicopter_world_messages(
            domain.make_world("wires", 3), wire_segments=8, frame_id="map", msgs=RclpyMessages()
        )
        peer.terrain.publish(cloud)
        peer.obstacles.publish(markers)
        assert spin_until(executor, lambda: node.snapshot.version >= 2)
        assert node.trigger_deactivate().name == "SUCCESS"
        goal = PoseStamped()
        goal.header.frame_id = "map"
        goal.pose.position.x, goal.pose.position.y, goal.pose.position.z = (float(v) for v in session.goal_state[:3])
        node.plan_for(goal)
        # planned ...
        assert node.history
        assert node.history[-1].result.ok
        spin_for(executor, 0.5)
        # ... but nothing went out
        assert not peer.plans
        assert not peer.checks
        assert node.published is None
        assert node.trigger_activate().name == "SUCCESS"
        node.plan_for(goal)
        assert spin_until(executor, lambda: bool(peer.plans) and bool(peer.checks))
