"""MoveIt planning scenes -> collision parts, with plain stand-ins for the messages (no ROS needed)."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from drd_planner.exceptions import GeometryError
from drd_planner.geometry.shapes import Box, Cylinder, Sphere, TriangleMesh
from drd_planner.planning.map_store import MapStore
from drd_planner.planning.moveit_world import ADD, APPEND, MOVE, REMOVE, MoveItWorld, object_key

#: Stand-ins for message objects (fields as attributes).
Msg = SimpleNamespace

FRAME = "world"


def pose(x: float = 0.0, y: float = 0.0, z: float = 0.0, q: tuple[float, ...] = (0.0, 0.0, 0.0, 1.0)) -> Msg:
    return Msg(position=Msg(x=x, y=y, z=z), orientation=Msg(x=q[0], y=q[1], z=q[2], w=q[3]))


def primitive(kind: int, *dims: float) -> Msg:
    return Msg(type=kind, dimensions=list(dims))


def tetra() -> Msg:
    points = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
    return Msg(
        vertices=[Msg(x=x, y=y, z=z) for x, y, z in points],
        triangles=[Msg(vertex_indices=t) for t in ([0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3])],
    )


def obj(name: str, *, op: int = ADD, frame: str = FRAME, at: Msg | None = None, **fields: Any) -> Msg:
    prims = fields.pop("primitives", [])
    meshes = fields.pop("meshes", [])
    msg = Msg(
        header=Msg(frame_id=frame),
        pose=at or pose(),
        id=name,
        primitives=prims,
        primitive_poses=fields.pop("primitive_poses", [pose() for _ in prims]),
        meshes=meshes,
        mesh_poses=fields.pop("mesh_poses", [pose() for _ in meshes]),
        planes=fields.pop("planes", []),
        plane_poses=fields.pop("plane_poses", []),
        subframe_names=fields.pop("subframe_names", []),
        subframe_poses=fields.pop("subframe_poses", []),
        operation=bytes([op]),  # rclpy gives a byte field as bytes
    )
    assert not fields, fields
    return msg


def scene(*objects: Msg, diff: bool = False, octomap: bytes = b"", attached: tuple[str, ...] = ()) -> Msg:
    return Msg(
        is_diff=diff,
        robot_state=Msg(attached_collision_objects=[Msg(object=Msg(id=a)) for a in attached]),
        world=Msg(
            collision_objects=list(objects),
            octomap=Msg(octomap=Msg(data=list(octomap), resolution=0.05)),
        ),
    )


def test_box_sphere_cylinder_and_mesh_placed_by_object_and_shape_poses() -> None:
    world = MoveItWorld(frame_id=FRAME)
    quarter = (0.0, 0.0, np.sin(np.pi / 4), np.cos(np.pi / 4))  # 90 degrees about z
    msg = obj(
        "table",
        at=pose(1.0, 0.0, 0.0, quarter),
        primitives=[primitive(1, 0.1, 0.2, 0.3), primitive(2, 0.05), primitive(3, 0.4, 0.1)],
        primitive_poses=[pose(0.5, 0.0, 0.0), pose(), pose()],
        meshes=[tetra()],
    )
    objects = world.apply(scene(msg))
    parts = objects["table"].parts()
    assert [type(s) for s, _ in parts] == [Box, Sphere, Cylinder, TriangleMesh]
    box, box_pose = parts[0]
    assert isinstance(box, Box)
    assert box.size.tolist() == [0.1, 0.2, 0.3]
    np.testing.assert_allclose(box_pose.position, [1.0, 0.5, 0.0], atol=1e-12)  # rotated by the object
    cylinder = parts[2][0]
    assert isinstance(cylinder, Cylinder)
    assert (cylinder.length, cylinder.radius) == (0.4, 0.1)  # MoveIt's order is [height, radius]
    assert world.parts().keys() == {object_key("table")}


def test_unset_quaternion_is_no_rotation_and_empty_frame_is_the_planning_frame() -> None:
    world = MoveItWorld(frame_id=FRAME)
    world.apply(scene(obj("b", frame="", at=pose(1, 2, 3, (0, 0, 0, 0)), primitives=[primitive(1, 1, 1, 1)])))
    ((_, where),) = world.objects["b"].parts()
    np.testing.assert_allclose(where.quaternion_xyzw, [0, 0, 0, 1])
    np.testing.assert_allclose(where.position, [1, 2, 3])


def test_diffs_add_append_move_remove_and_a_full_scene_replaces() -> None:
    world = MoveItWorld(frame_id=FRAME)
    world.apply(scene(obj("a", primitives=[primitive(2, 0.1)]), obj("b", primitives=[primitive(2, 0.1)])))
    appended = obj("a", op=APPEND, at=pose(9, 9, 9), primitives=[primitive(2, 0.2)], primitive_poses=[pose(0, 0, 1)])
    world.apply(scene(appended, diff=True))  # relative to the object's pose; the message's pose is not read
    assert len(world.objects["a"].shapes) == 2
    world.apply(scene(obj("a", op=MOVE, at=pose(5, 0, 0)), diff=True))
    positions = [p.position.tolist() for _, p in world.objects["a"].parts()]
    assert positions == [[5, 0, 0], [5, 0, 1]]  # the appended sphere moved with the object
    world.apply(scene(obj("b", op=REMOVE), diff=True))
    assert set(world.objects) == {"a"}
    world.apply(scene(obj("c", primitives=[primitive(1, 1, 1, 1)])))  # full scene: only c
    assert set(world.objects) == {"c"}
    world.apply(scene(obj("", op=REMOVE), diff=True))  # an empty id removes every object
    assert world.objects == {}


def test_subframes_are_kept_relative_to_the_object() -> None:
    world = MoveItWorld(frame_id=FRAME)
    msg = obj("a", primitives=[primitive(2, 0.1)], subframe_names=["tip"], subframe_poses=[pose(0, 0, 0.2)])
    world.apply(scene(msg))
    assert world.objects["a"].subframes["tip"].position.tolist() == [0, 0, 0.2]


@pytest.mark.parametrize(
    ("bad", "text"),
    [
        (scene(obj("a", primitives=[primitive(4, 1.0, 0.5)])), "CONE"),
        (scene(obj("a", primitives=[primitive(3, 0.5)])), "(height, radius)"),
        (scene(obj("a", primitives=[primitive(1, 1.0, 0.0, 1.0)])), "> 0"),
        (scene(obj("a", primitives=[primitive(1, 1.0, float("nan"), 1.0)])), "finite"),
        (scene(obj("a", frame="camera", primitives=[primitive(2, 1.0)])), "does no transforms"),
        (scene(obj("a", planes=[Msg(coef=[0, 0, 1, 0])], plane_poses=[pose()])), "planes"),
        (scene(obj("a", primitives=[primitive(2, 1.0)], primitive_poses=[])), "primitive_poses"),
        (scene(obj("a", at=pose(q=(0.0, 0.0, 0.5, 0.5)), primitives=[primitive(2, 1.0)])), "unit quaternion"),
        (scene(obj("a")), "no primitives or meshes"),
        (scene(obj("ghost", op=REMOVE), diff=True), "does not have"),
        (scene(obj("ghost", op=MOVE), diff=True), "does not have"),
        (scene(octomap=b"\x01\x02"), "octomaps are not supported"),
        (scene(attached=("cup",)), "attaches objects"),
    ],
)
def test_refusals_say_why_and_change_nothing(bad: Msg, text: str) -> None:
    world = MoveItWorld(frame_id=FRAME)
    world.apply(scene(obj("keep", primitives=[primitive(2, 0.1)])))
    with pytest.raises(GeometryError, match=None) as info:
        world.apply(bad)
    assert text in str(info.value)
    assert set(world.objects) == {"keep"}


def test_map_store_holds_scene_objects_beside_marker_obstacles() -> None:
    store = MapStore(frame_id=FRAME)
    first = store.apply("monitored_planning_scene", scene(obj("a", primitives=[primitive(2, 0.1)])))
    assert first is not None
    assert set(first.obstacles) == {"moveit:a"}
    second = store.apply(
        "/ns/monitored_planning_scene",
        scene(obj("b", primitives=[primitive(1, 1, 1, 1)]), diff=True),
    )
    assert second is not None
    assert second.version == first.version + 1
    assert set(second.obstacles) == {"moveit:a", "moveit:b"}
    assert second.obstacles["moveit:a"] is first.obstacles["moveit:a"]  # untouched parts kept as they were
    with pytest.raises(GeometryError, match="octomap"):
        store.apply("monitored_planning_scene", scene(octomap=b"\x01"))
    assert store.snapshot is second


def test_a_marker_update_keeps_the_scene_objects_and_a_scene_keeps_the_markers() -> None:
    pytest.importorskip("visualization_msgs.msg", reason="the MarkerArray type (ROS or the PyPI wheels)")
    from drd_msgs_py.factory import RclpyMessages
    from drd_planner.geometry.pose import Pose
    from drd_planner.planning.world_messages import obstacle_markers

    store = MapStore(frame_id=FRAME)
    store.apply("monitored_planning_scene", scene(obj("a", primitives=[primitive(2, 0.1)])))
    markers = obstacle_markers([("m/1", Box((1.0, 1.0, 1.0)), Pose())], frame_id=FRAME, msgs=RclpyMessages())
    after_markers = store.apply("obstacles", markers)
    assert after_markers is not None
    assert {"moveit:a", "m/1"} <= set(after_markers.obstacles)
    after_scene = store.apply("monitored_planning_scene", scene(obj("b", primitives=[primitive(2, 0.1)])))
    assert after_scene is not None
    assert "moveit:a" not in after_scene.obstacles  # a full scene replaced the scene's objects
    assert {"moveit:b", "m/1"} <= set(after_scene.obstacles)
