"""Sampled worlds and collision shapes as the messages a map server would send (for bags, demos and tests).

Helicopter: wires become LINE_STRIPs through the knots of the capsule chain the planner's own scene uses
(``wire_segments`` capsules per span) with ``scale.x`` the chain's diameter (the wire's plus twice the
chord error), so the node's scene from these messages equals ``HelicopterDomain.scene(world)``.
Towers and no-fly zones become CYLINDER / CUBE markers, the terrain an organized cloud.

Arm: each posed primitive (box, cylinder, sphere) of an ``ArmWorld`` becomes one CUBE / CYLINDER /
SPHERE marker in the robot's root frame, so the node's scene from them equals ``ArmWorld.to_scene()``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from drd_msgs_py.factory import MessageFactory
from drd_msgs_py.obstacles import MarkerStyle, markers_from_obstacles
from drd_msgs_py.terrain import cloud_from_heightfield
from drd_planner.arrays import FloatArray
from drd_planner.domains.arm_worlds import ArmWorld
from drd_planner.domains.helicopter_worlds import HelicopterWorld
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Shape
from drd_planner.planning.map_intake import obstacles_data

if TYPE_CHECKING:
    from typing_extensions import Unpack

__all__ = ["arm_world_messages", "helicopter_world_messages", "obstacle_markers"]


def obstacle_markers(
    obstacles: Sequence[tuple[str, Shape | FloatArray, Pose | float]],
    *,
    frame_id: str,
    msgs: MessageFactory,
    **style: Unpack[MarkerStyle],
) -> Any:
    """A MarkerArray of collision shapes (:func:`drd_msgs_py.obstacles.markers_from_obstacles` of their data).

    Args:
        obstacles: ``(key, shape, pose)`` for Box, Sphere, Cylinder and TriangleMesh, or
            ``(key, points, diameter)`` with (K >= 2, 3) world points for a wire (LINE_STRIP).
            Keys look like ``"ns/id"``.
        frame_id: the frame of every marker.
        msgs: the message factory (rclpy or rosbags classes).
        style: ``stamp``, ``delete_all_first`` and ``color`` (:class:`~drd_msgs_py.obstacles.MarkerStyle`),
            passed on; those left out take the defaults of ``markers_from_obstacles``.

    Raises:
        GeometryError: a shape with no marker form (a bare Capsule: send it as a two-point LINE_STRIP).
        MessageError: a key that is not ``ns/id``.
    """
    return markers_from_obstacles(obstacles_data(obstacles), frame_id=frame_id, msgs=msgs, **style)


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
    markers = obstacle_markers(obstacles, frame_id=frame_id, stamp=stamp, msgs=msgs)
    cloud = cloud_from_heightfield(world.terrain, frame_id=frame_id, stamp=stamp, msgs=msgs)
    return markers, cloud


def arm_world_messages(
    world: ArmWorld,
    *,
    frame_id: str = "panda_link0",
    stamp: tuple[int, int] = (0, 0),
    msgs: MessageFactory,
) -> Any:
    """MarkerArray (DELETEALL first) of an arm world's solids, in the robot's root frame.

    Each primitive keeps its name as the marker namespace (id 0; key ``<name>/0``), so RViz lists
    ``table_top``, ``box_3``, ... and an update can replace one object by name.

    Args:
        world: the world (primitives: Box, Cylinder along local +z, Sphere; sizes and poses in metres).
        frame_id: the robot's root frame (``panda_link0`` for the Panda).
        stamp: (sec, nanosec) of the headers.
        msgs: the message factory (rclpy or rosbags classes).
    """
    obstacles: list[tuple[str, Any, Any]] = [(f"{p.name}/0", p.shape, p.pose) for p in world.obstacles]
    return obstacle_markers(obstacles, frame_id=frame_id, stamp=stamp, msgs=msgs)
