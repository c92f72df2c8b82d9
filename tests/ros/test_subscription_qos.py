"""The QoS of the node's subscriptions: what each profile promises its publishers."""

from __future__ import annotations

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")

from rclpy.qos import DurabilityPolicy, ReliabilityPolicy

from drd_planner.ros.subscription_qos import REQUESTS, ROBOT_STATE, VOLATILE_MAPS


def test_each_profile_hears_the_publishers_it_is_for() -> None:
    # Volatile maps: reliable and volatile, so volatile publishers (perception nodes, RViz tools) match too.
    assert VOLATILE_MAPS.durability == DurabilityPolicy.VOLATILE
    assert VOLATILE_MAPS.reliability == ReliabilityPolicy.RELIABLE
    assert VOLATILE_MAPS.depth == 1
    # The robot's state: best effort matches best-effort and reliable publishers alike; only the newest counts.
    assert ROBOT_STATE.reliability == ReliabilityPolicy.BEST_EFFORT
    assert ROBOT_STATE.depth <= 10
    # Requests: reliable and deep, so a burst is coalesced by the node rather than dropped by the middleware.
    assert REQUESTS.reliability == ReliabilityPolicy.RELIABLE
    assert REQUESTS.depth >= 1000
