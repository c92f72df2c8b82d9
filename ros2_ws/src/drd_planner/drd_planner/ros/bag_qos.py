"""QoS between rosbag2 files (rosbags' ``Qos``) and rclpy (``QoSProfile``), for replaying and recording.

A bag stores each channel's *offered* QoS; :func:`rclpy_qos` turns it into the profile a replay publisher
uses, and :func:`offered_qos` reads what a live publisher offers from the ROS graph, for recording it.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rosbags.interfaces import Qos, QosDurability, QosReliability

from drd_msgs_py.bags import default_qos, topic_base

__all__ = ["offered_qos", "rclpy_qos"]


def rclpy_qos(profile: Qos | None, topic: str) -> QoSProfile:
    """The rclpy profile of a bag's offered QoS (keep-last; ``None`` or unknown policies: :func:`default_qos`)."""
    fallback = default_qos(topic)
    chosen = profile or fallback
    reliability = ReliabilityPolicy.RELIABLE
    if chosen.reliability == QosReliability.BEST_EFFORT:
        reliability = ReliabilityPolicy.BEST_EFFORT
    durable = chosen.durability
    if durable not in (QosDurability.VOLATILE, QosDurability.TRANSIENT_LOCAL):  # system default, unknown
        durable = fallback.durability
    durability = (
        DurabilityPolicy.TRANSIENT_LOCAL if durable == QosDurability.TRANSIENT_LOCAL else DurabilityPolicy.VOLATILE
    )
    depth = chosen.depth if chosen.depth > 0 else fallback.depth
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=reliability, durability=durability)


def offered_qos(node: Any, topic: str, *, latched: Sequence[str] = ()) -> Qos:
    """The QoS a publisher of ``topic`` offers according to the ROS graph (history: our rule).

    ``latched``: topic bases taken as transient_local when no publisher is found in the graph.
    """
    base = topic_base(topic)
    rule = default_qos(topic, latched=tuple(latched))
    infos = node.get_publishers_info_by_topic(topic)
    if not infos:
        return rule
    offered = infos[0].qos_profile
    is_latched = offered.durability == DurabilityPolicy.TRANSIENT_LOCAL
    best_effort = offered.reliability == ReliabilityPolicy.BEST_EFFORT
    out = default_qos(base, latched=(base,) if is_latched else ())
    return out._replace(reliability=QosReliability.BEST_EFFORT) if best_effort else out
