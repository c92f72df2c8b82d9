"""Small rosbags messages of a helicopter scene, shared by the bag tests (``tests/msgs``, ``tests/planning``).

Importable from every test module: ``tests/`` is on ``sys.path`` because of the root ``conftest.py``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from drd_msgs_py.bags import BagMessage
from drd_msgs_py.factory import RosbagsMessages, header
from drd_msgs_py.terrain import cloud_from_heightfield
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Box, Cylinder, Sphere
from drd_planner.geometry.terrain import Heightfield
from drd_planner.planning.world_messages import obstacle_markers

T0 = 1_000_000_000_000
"""A bag start time in nanoseconds."""
SEC = 10**9
"""Nanoseconds per second."""


def stamp(t: int) -> tuple[int, int]:
    """``(sec, nanosec)`` of ``t`` nanoseconds."""
    return t // SEC, t % SEC


def terrain_message(rb: RosbagsMessages, t: int) -> BagMessage:
    """A 6 x 9 terrain cloud of 10 m cells in ``map`` at ``t`` (heights seeded, 0-20 m)."""
    rng = np.random.default_rng(3)
    field = Heightfield((-50.0, -40.0), 10.0, rng.uniform(0.0, 20.0, size=(6, 9)))
    cloud = cloud_from_heightfield(field, frame_id="map", stamp=stamp(t), msgs=rb)
    return BagMessage("/terrain", "sensor_msgs/msg/PointCloud2", t, cloud)


def obstacles_message(rb: RosbagsMessages, t: int, extra: bool = False, frame: str = "map") -> BagMessage:
    """A tower, a no-fly box and a wire at ``t`` (with ``extra``, a new sphere as well)."""
    items: list[tuple[str, Any, Any]] = [
        ("tower/0", Cylinder(2.0, 60.0), Pose((10.0, 0.0, 30.0))),
        ("nofly/1", Box((40.0, 30.0, 200.0)), Pose((-20.0, 10.0, 100.0))),
        ("wire/2", np.array([[0.0, -30.0, 40.0], [0.0, 0.0, 35.0], [0.0, 30.0, 40.0]]), 0.1),
    ]
    if extra:
        items.append(("new_obstacle/0", Sphere(3.0), Pose((5.0, 5.0, 50.0))))
    markers = obstacle_markers(items, frame_id=frame, stamp=stamp(t), msgs=rb)
    return BagMessage("/obstacles", "visualization_msgs/msg/MarkerArray", t, markers)


def goal_message(rb: RosbagsMessages, t: int, xyz: tuple[float, float, float], frame: str = "map") -> BagMessage:
    """A ``/goal_pose`` at ``xyz`` (m) in ``frame``, identity orientation, at ``t``."""
    pose = rb(
        "geometry_msgs/msg/Pose",
        position=rb("geometry_msgs/msg/Point", x=xyz[0], y=xyz[1], z=xyz[2]),
        orientation=rb("geometry_msgs/msg/Quaternion", x=0.0, y=0.0, z=0.0, w=1.0),
    )
    msg = rb("geometry_msgs/msg/PoseStamped", header=header(rb, frame, stamp(t)), pose=pose)
    return BagMessage("/goal_pose", "geometry_msgs/msg/PoseStamped", t, msg)
