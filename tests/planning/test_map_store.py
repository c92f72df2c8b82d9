"""The one map store: messages applied as the node applies them, refusals leave the maps, bag maps at requests."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from bag_messages import SEC, T0, goal_message, obstacles_message, terrain_message

import drd_msgs_py.obstacles as obstacles_module
import drd_planner.planning.map_store as map_store_module
from drd_msgs_py import marker_cdr
from drd_msgs_py.bags import BagMessage, bag_requests, jazzy_typestore, read_bag, write_bag
from drd_msgs_py.exceptions import MessageError
from drd_msgs_py.factory import RosbagsMessages
from drd_msgs_py.obstacles import Obstacle, obstacle_update
from drd_msgs_py.terrain import cloud_from_heightfield
from drd_planner.domains.base import domain_from_spec
from drd_planner.exceptions import DrdError
from drd_planner.geometry.map_limits import MapLimits
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Box, Sphere
from drd_planner.geometry.terrain import Heightfield
from drd_planner.planning.bag_plan import maps_at_request, maps_until
from drd_planner.planning.map_intake import obstacle_parts
from drd_planner.planning.map_store import MapStore, terrain_fit_of
from drd_planner.planning.world_messages import obstacle_markers


@pytest.fixture
def rb() -> RosbagsMessages:
    return RosbagsMessages(jazzy_typestore())


def _scenario(rb: RosbagsMessages) -> list[BagMessage]:
    """Maps at 0, a request at 0.5 s, a refused map (wrong frame) at 1 s, an update at 1.5 s, a request at 2.5 s."""
    return [
        terrain_message(rb, T0),
        obstacles_message(rb, T0),
        goal_message(rb, T0 + SEC // 2, (100.0, 0.0, 40.0)),
        obstacles_message(rb, T0 + SEC, extra=True, frame="odom"),
        obstacles_message(rb, T0 + 3 * SEC // 2, extra=True),
        goal_message(rb, T0 + 5 * SEC // 2, (100.0, 0.0, 40.0)),
    ]


def test_maps_at_each_request_are_what_the_node_applies(rb: RosbagsMessages, tmp_path: Path) -> None:
    messages = read_bag(write_bag(tmp_path / "m.mcap", _scenario(rb)))
    assert len(bag_requests(messages)) == 2
    first, req0 = maps_at_request(messages, 0, frame_id="map", margin=2.0)
    assert (req0.index, req0.position) == (0, 2)
    snap = first.snapshot
    assert snap.version == 2
    assert snap.margin == 2.0
    assert first.applied == 2
    assert not first.refused
    expected = obstacle_update(obstacles_message(rb, T0).message, frame_id="map").apply({})
    assert set(snap.obstacles) == set(expected) == set(first.obstacles) == {"tower/0", "nofly/1", "wire/2"}
    assert all(snap.obstacles[k] == obstacle_parts(expected[k]) for k in expected)
    assert snap.terrain is not None
    assert snap.terrain.shape == (6, 9)
    # The wrong-frame update is refused (map unchanged, version not bumped); the next one is applied.
    second, _ = maps_at_request(messages, 1, frame_id="map", margin=2.0)
    assert second.snapshot.version == 3
    assert len(second.refused) == 1
    assert "frame 'odom'" in second.refused[0]
    assert set(second.snapshot.obstacles) == {"tower/0", "nofly/1", "wire/2", "new_obstacle/0"}
    # The new sphere is really in the scene at request 1 and not at request 0.
    probe = (np.array([[5.0, 5.0, 50.0]]), np.array([0.5]))
    assert second.snapshot.scene.spheres_collide(*probe)
    assert not snap.scene.spheres_collide(*probe)
    # maps_until is inclusive in time and agrees with maps_at_request.
    until = maps_until(messages, T0 + 3 * SEC // 2, frame_id="map", margin=2.0)
    assert until.snapshot.version == 3
    assert set(until.snapshot.obstacles) == set(second.snapshot.obstacles)
    assert maps_until(messages, T0 + 3 * SEC // 2 - 1, frame_id="map", margin=2.0).snapshot.version == 2
    # A planner in another frame refuses every map.
    other, _ = maps_at_request(messages, 0, frame_id="odom", margin=0.0)
    assert other.snapshot.version == 0
    assert len(other.refused) == 2


def test_robot_description_goes_through_the_given_loader(rb: RosbagsMessages) -> None:
    text = BagMessage("/robot_description", "std_msgs/msg/String", T0, rb("std_msgs/msg/String", data="<robot/>"))
    messages = [text, obstacles_message(rb, T0), goal_message(rb, T0 + 1, (0.0, 0.0, 0.0))]
    plain, _ = maps_at_request(messages, 0, frame_id="map", margin=0.0)
    assert plain.robot_description == "<robot/>"
    assert plain.snapshot.version == 1
    assert plain.snapshot.robot is None

    def refuse(_urdf: str) -> Any:
        raise DrdError("no such robot")

    refused, _ = maps_at_request(messages, 0, frame_id="map", margin=0.0, robot_loader=refuse)
    assert refused.snapshot.version == 1
    assert "robot_description" in refused.refused[0]


def test_unchanged_obstacles_keep_their_parts_and_a_refusal_keeps_the_map(rb: RosbagsMessages) -> None:
    store = MapStore(frame_id="map", margin=1.0, limits=MapLimits(max_markers=4))
    first = store.apply("/obstacles", obstacles_message(rb, T0).message)
    assert first is not None
    assert first.version == 1
    assert first.margin == 1.0
    update = obstacle_markers(
        [("new_obstacle/0", Sphere(3.0), Pose((5.0, 5.0, 50.0)))],
        frame_id="map",
        msgs=rb,
        delete_all_first=False,
    )
    second = store.apply_obstacles(update)
    assert second.obstacles["tower/0"] is first.obstacles["tower/0"]  # not rebuilt: the scene reuses it
    assert second.cache is first.cache  # one scene cache per store
    more = obstacle_markers([("more/0", Sphere(1.0), Pose())], frame_id="map", msgs=rb, delete_all_first=False)
    with pytest.raises(MessageError, match="max_markers = 4"):
        store.apply_obstacles(more)
    assert store.snapshot is second
    assert set(store.obstacles) == set(second.obstacles)
    with pytest.raises(MessageError, match="frame 'odom'"):
        store.apply("obstacles", obstacles_message(rb, T0, frame="odom").message)
    terrain = store.apply("terrain", terrain_message(rb, T0).message)
    assert terrain is not None
    assert terrain.version == 3
    assert terrain.terrain is not None
    assert store.apply("goal_pose", goal_message(rb, T0, (0.0, 0.0, 0.0)).message) is None
    assert store.apply("robot_description", rb("std_msgs/msg/String", data="<robot/>")) is None
    assert store.robot_description == "<robot/>"
    assert not store.has_robot_loader


def test_a_terrain_no_loaded_prior_can_stand_on_is_refused_and_the_maps_are_kept(rb: RosbagsMessages) -> None:
    """Issue 33 item 17: a terrain 20 km off the helicopter lattice is refused with both extents named."""
    heli = domain_from_spec("helicopter")
    store = MapStore(frame_id="map", terrain_fit=terrain_fit_of([heli]))
    good = store.apply("terrain", terrain_message(rb, T0).message)
    assert good is not None
    assert good.version == 1
    far = Heightfield((20_000.0, 20_000.0), 10.0, np.zeros((4, 5)))
    cloud = cloud_from_heightfield(far, frame_id="map", stamp=(1, 0), msgs=rb)
    with pytest.raises(DrdError, match=r"not the prior's terrain: the terrain spans x \[20000, 20040\] m"):
        store.apply("terrain", cloud)
    assert store.snapshot is good
    # A prior whose domain has no terrain model takes any terrain, so the pair takes this one.
    both = MapStore(frame_id="map", terrain_fit=terrain_fit_of([heli, domain_from_spec("planar")]))
    assert both.apply("terrain", cloud) is not None


# --------------------------------------------------------------------------------------------------
# Issue 33 item 5: a latched topic re-sends the whole map; an update costs what changed


def _grid_of_cubes(rb: RosbagsMessages, count: int, *, moved: float = 0.0, serialized: bool) -> Any:
    """DELETEALL then ``count`` 1 m cubes 3 m apart along x at z = 5 m, cube ``box/7`` ``moved`` metres along x."""
    cubes = [
        (f"box/{k}", Box((1.0, 1.0, 1.0)), Pose((3.0 * k + (moved if k == 7 else 0.0), 0.0, 5.0))) for k in range(count)
    ]
    msg = obstacle_markers(cubes, frame_id="map", msgs=rb)
    if serialized:  # as the node's raw subscription takes it
        return bytes(rb.typestore.serialize_cdr(msg, "visualization_msgs/msg/MarkerArray"))
    return msg


@pytest.mark.parametrize("serialized", [False, True], ids=["message", "serialized"])
@pytest.mark.parametrize("count", [40, 400])
def test_a_republished_map_builds_only_the_moved_marker(
    rb: RosbagsMessages, monkeypatch: pytest.MonkeyPatch, count: int, serialized: bool
) -> None:
    """The whole map again with one cube moved: one obstacle's parts built (not ``count``), the scene has it moved.

    Counts of work, not seconds: the same at 40 and 400 cubes. A serialized array is not even converted
    again except for the moved marker (the same bytes passed the same checks).
    """
    store = MapStore(frame_id="map", limits=MapLimits(max_markers=count + 1))
    first = store.apply_obstacles(_grid_of_cubes(rb, count, serialized=serialized))
    assert first.scene.spheres_collide_mask([[21.0, 0.0, 5.0]], 0.2).tolist() == [True]
    built: list[str] = []
    converted: list[str] = []
    real_parts, real_obstacle = map_store_module.obstacle_parts, obstacles_module._obstacle

    def counted_parts(obstacle: Obstacle) -> Any:
        built.append(obstacle.key)
        return real_parts(obstacle)

    def counted_obstacle(marker: Any, key: str, what: str) -> Obstacle:
        converted.append(key)
        return real_obstacle(marker, key, what)

    read: list[int] = []
    real_read = marker_cdr._Reader.marker

    def counted_read(reader: Any, i: int) -> Any:
        read.append(i)
        return real_read(reader, i)

    monkeypatch.setattr(map_store_module, "obstacle_parts", counted_parts)
    monkeypatch.setattr(obstacles_module, "_obstacle", counted_obstacle)
    monkeypatch.setattr(marker_cdr._Reader, "marker", counted_read)
    second = store.apply_obstacles(_grid_of_cubes(rb, count, moved=1.5, serialized=serialized))
    assert built == ["box/7"]
    assert converted == (["box/7"] if serialized else [f"box/{k}" for k in range(count)])
    assert read == ([8] if serialized else [])  # the bytes of the others are unchanged: not read again
    assert second.version == 2
    assert set(second.obstacles) == set(first.obstacles)
    assert all(second.obstacles[k] is first.obstacles[k] for k in first.obstacles if k != "box/7")
    assert store.obstacles["box/7"].pose.position == (22.5, 0.0, 5.0)
    # The moved cube's new place (x 22 to 23) is blocked, its old place (x 20.5 to 21.5) free
    probes = [[22.5, 0.0, 5.0], [21.0, 0.0, 5.0], [24.0, 0.0, 5.0]]
    assert second.scene.spheres_collide_mask(probes, 0.2).tolist() == [True, False, True]
    built.clear()
    converted.clear()
    third = store.apply_obstacles(_grid_of_cubes(rb, count, moved=1.5 + 1e-9, serialized=serialized))
    assert built == ["box/7"]  # a nanometre is a change: never kept as equal
    assert converted == (["box/7"] if serialized else [f"box/{k}" for k in range(count)])
    assert third.obstacles["box/7"] is not second.obstacles["box/7"]
    assert third.scene.spheres_collide_mask(probes, 0.2).tolist() == [True, False, True]
