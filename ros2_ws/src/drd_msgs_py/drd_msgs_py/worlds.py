"""A sampled helicopter world as the messages a map server would send (for bags, demos and tests).

Wires become LINE_STRIPs through the knots of the capsule chain the planner's own scene uses
(``wire_segments`` capsules per span) with ``scale.x`` the chain's diameter (the wire's plus twice the
chord error), so the node's scene from these messages equals ``HelicopterDomain.scene(world)``.
Towers and no-fly zones become CYLINDER / CUBE markers, the terrain an organized cloud.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from drd_msgs_py.factory import MessageFactory
from drd_msgs_py.obstacles import markers_from_obstacles
from drd_msgs_py.terrain import cloud_from_heightfield
from drd_planner.domains.helicopter_worlds import HelicopterWorld

__all__ = ["helicopter_world_messages"]


def helicopter_world_messages(
    world: HelicopterWorld,
    *,
    wire_segments: int | None,
    frame_id: str = "map",
    stamp: tuple[int, int] = (0, 0),
    msgs: MessageFactory,
) -> tuple[Any, Any]:
    """(MarkerArray of obstacles starting with DELETEALL, PointCloud2 of the terrain).

    Args:
        world: the sampled world.
        wire_segments: capsules per wire span, as in the domain (None: each wire's default).
        frame_id: frame of every message.
        stamp: (sec, nanosec) of the headers.
        msgs: the message factory (rclpy or rosbags classes).
    """
    obstacles: list[tuple[str, Any, Any]] = []
    for i, wire in enumerate(world.wires):
        n = wire.default_segments() if wire_segments is None else wire_segments
        diameter = wire.diameter + 2.0 * wire.sag / n**2
        obstacles.append((f"wire/{i}", np.asarray(wire.points(n + 1)), diameter))
    for k, (_name, shape, pose) in enumerate(world.solids):
        obstacles.append((f"solid/{k}", shape, pose))
    markers = markers_from_obstacles(obstacles, frame_id=frame_id, stamp=stamp, msgs=msgs)
    cloud = cloud_from_heightfield(world.terrain, frame_id=frame_id, stamp=stamp, msgs=msgs)
    return markers, cloud
