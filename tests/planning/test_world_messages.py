"""Worlds and collision shapes as map messages: what the map store rebuilds from them is the world."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from drd_msgs_py.exceptions import MessageError
from drd_msgs_py.obstacles import obstacle_update
from drd_planner.domains.arm_worlds import ArmWorld
from drd_planner.exceptions import GeometryError
from drd_planner.geometry.moveit_scene import ScenePrimitive
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Box, Capsule, Cylinder, Sphere
from drd_planner.planning.map_intake import obstacle_parts
from drd_planner.planning.world_messages import arm_world_messages, obstacle_markers


def test_arm_world_markers_rebuild_the_world(msgs: Any) -> None:
    world = ArmWorld(
        (
            ScenePrimitive("table_top", Box((0.8, 1.2, 0.04)), Pose((0.6, 0.0, 0.1), (0.0, 0.0, 0.1, 0.995))),
            ScenePrimitive("cylinder_1", Cylinder(0.04, 0.3), Pose((0.5, 0.2, 0.27))),
            ScenePrimitive("obj/2", Sphere(0.05), Pose((0.4, -0.3, 0.2))),
        ),
        "table_clutter",
        7,
    )
    markers = arm_world_messages(world, frame_id="panda_link0", stamp=(3, 4), msgs=msgs)
    got = obstacle_update(markers, frame_id="panda_link0").apply({})
    assert set(got) == {"table_top/0", "cylinder_1/0", "obj/2/0"}
    for p in world.obstacles:
        ((shape, pose),) = obstacle_parts(got[f"{p.name}/0"])
        assert shape == p.shape
        np.testing.assert_allclose(pose.position, p.pose.position, atol=1e-12)
        np.testing.assert_allclose(
            np.abs(pose.quaternion_xyzw @ p.pose.quaternion_xyzw), 1.0, atol=1e-9
        )  # same rotation
    with pytest.raises(MessageError, match="frame"):
        obstacle_update(markers, frame_id="map")


def test_shapes_without_a_marker_form_and_bad_keys_are_refused(msgs: Any) -> None:
    with pytest.raises(GeometryError, match="cap/0: Capsule has no marker form"):
        obstacle_markers([("cap/0", Capsule(1.0, 2.0), Pose())], frame_id="map", msgs=msgs)
    with pytest.raises(MessageError, match="ns/<int id>"):
        obstacle_markers([("nokey", Sphere(1.0), Pose())], frame_id="map", msgs=msgs)


def test_the_marker_style_is_passed_on(msgs: Any) -> None:
    items: list[tuple[str, Any, Any]] = [("ball/0", Sphere(0.5), Pose((1.0, 2.0, 3.0)))]
    plain = obstacle_markers(items, frame_id="map", msgs=msgs)
    assert [m.action for m in plain.markers] == [3, 0]  # DELETEALL first by default
    assert (plain.markers[1].header.stamp.sec, plain.markers[1].color.r) == (0, pytest.approx(0.8))
    styled = obstacle_markers(
        items, frame_id="map", msgs=msgs, stamp=(5, 6), delete_all_first=False, color=(0.0, 1.0, 0.0, 1.0)
    )
    (marker,) = styled.markers
    assert (marker.header.stamp.sec, marker.header.stamp.nanosec) == (5, 6)
    assert (marker.color.r, marker.color.g, marker.color.b, marker.color.a) == (0.0, 1.0, 0.0, 1.0)
