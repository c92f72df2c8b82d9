"""Map QoS: a latched map reaches the default node, a default-QoS (volatile) publisher the volatile one."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

rclpy = pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")

from harness import private_context, spin_until, use_domain  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.lifecycle import TransitionCallbackReturn  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from sensor_msgs.msg import PointCloud2  # noqa: E402
from visualization_msgs.msg import MarkerArray  # noqa: E402

from drd_msgs_py.factory import RclpyMessages  # noqa: E402
from drd_planner.domains.helicopter import HelicopterDomain  # noqa: E402
from drd_planner.planner import load_prior  # noqa: E402
from drd_planner.planning.session import QuerySession  # noqa: E402
from drd_planner.planning.world_messages import helicopter_world_messages  # noqa: E402
from drd_planner.ros.node import LATCHED, PlannerNode  # noqa: E402

TREE = Path(__file__).resolve().parents[2] / "trees" / "heli_wires.npz"
use_domain(100)


@pytest.fixture
def context() -> Iterator[Any]:
    with private_context() as ctx:
        yield ctx


def _maps_reach_the_node(ctx: Any, *, transient_local: bool, publisher_qos: Any, before: bool) -> bool:
    """Publish the wires world (before or after the node is active); whether the node takes both maps."""
    node = PlannerNode(
        context=ctx,
        parameter_overrides=[
            Parameter("prior_paths", value=[str(TREE)]),
            Parameter("map_subscribe_transient_local", value=transient_local),
        ],
    )
    peer = rclpy.create_node("map_publisher", context=ctx)
    executor = SingleThreadedExecutor(context=ctx)
    executor.add_node(node)
    executor.add_node(peer)
    try:
        domain = _domain()
        markers, cloud = helicopter_world_messages(
            domain.make_world("wires", 3), wire_segments=8, frame_id="map", msgs=RclpyMessages()
        )
        obstacles = peer.create_publisher(MarkerArray, "obstacles", publisher_qos)
        terrain = peer.create_publisher(PointCloud2, "terrain", publisher_qos)

        def publish() -> None:
            terrain.publish(cloud)
            obstacles.publish(markers)

        if before:
            publish()
        assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS
        assert node.trigger_activate() == TransitionCallbackReturn.SUCCESS
        # Wait until the publishers have matched whatever they can match, then publish (again).
        spin_until(executor, lambda: obstacles.get_subscription_count() > 0, timeout=3.0)
        if not before:
            publish()
        return spin_until(executor, lambda: node.snapshot.version >= 2, timeout=4.0)
    finally:
        executor.shutdown()
        node.destroy_node()
        peer.destroy_node()


def _domain() -> HelicopterDomain:
    """The helicopter domain of the tree (rebuilt from the tree file's spec)."""
    domain = QuerySession(load_prior(TREE), name="tree").domain
    assert isinstance(domain, HelicopterDomain)
    return domain


def test_a_latched_map_published_before_the_node_started_reaches_the_default_node(context: Any) -> None:
    assert _maps_reach_the_node(context, transient_local=True, publisher_qos=LATCHED, before=True)


@pytest.mark.slow
def test_a_default_qos_publisher_reaches_the_node_with_volatile_map_subscriptions(context: Any) -> None:
    assert not _maps_reach_the_node(context, transient_local=True, publisher_qos=10, before=False)  # DDS refuses
    assert _maps_reach_the_node(context, transient_local=False, publisher_qos=10, before=False)
    assert _maps_reach_the_node(context, transient_local=False, publisher_qos=LATCHED, before=False)


def test_map_qos_can_be_overridden_and_survives_reactivation(context: Any) -> None:
    node = PlannerNode(
        context=context,
        parameter_overrides=[
            Parameter("prior_paths", value=[str(TREE)]),
            Parameter("qos_overrides./terrain.subscription.depth", value=3),
        ],
    )
    try:
        assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS
        for _ in range(2):
            assert node.trigger_activate() == TransitionCallbackReturn.SUCCESS
            (terrain,) = [s for s in node.subscriptions if s.topic_name == "/terrain"]
            assert terrain.qos_profile.depth == 3
            assert node.trigger_deactivate() == TransitionCallbackReturn.SUCCESS
    finally:
        node.destroy_node()
