"""The QoS of the planner node's subscriptions (its publishers' are in :mod:`drd_planner.ros.outputs`)."""

from __future__ import annotations

from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

__all__ = ["REQUESTS", "ROBOT_STATE", "VOLATILE_MAPS"]

#: Map subscriptions with ``map_subscribe_transient_local`` false: hears volatile and latched publishers.
VOLATILE_MAPS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE)
#: The robot's state (odometry, joint states): best effort, which hears reliable publishers too.
ROBOT_STATE = QoSProfile(depth=5, reliability=ReliabilityPolicy.BEST_EFFORT)
#: Requests (topics and the service): reliable and deep enough that a burst reaches the node, which then
#: coalesces it (with KEEP_LAST 10 the middleware would drop all but the last 10 unseen).
REQUESTS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
