"""MarkerArray <-> marker shapes (plain data): round trips, exact values, and every refusal."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

import drd_msgs_py.obstacles as obstacles_module
from drd_msgs_py.exceptions import MessageError
from drd_msgs_py.factory import RclpyMessages, RosbagsMessages
from drd_msgs_py.limits import MessageLimits
from drd_msgs_py.obstacles import CUBE, LINE_STRIP, markers_from_obstacles, obstacle_update, same_obstacle
from drd_msgs_py.shapes import BoxData, CylinderData, LineStripData, MeshData, PoseData, SphereData

FRAME = "map"


class SerializedMessages(RosbagsMessages):
    """rosbags messages, except that a MarkerArray comes out serialized (what the node's raw subscription gets)."""

    def __call__(self, type_name: str, /, **fields: Any) -> Any:
        msg = super().__call__(type_name, **fields)
        if type_name == "visualization_msgs/msg/MarkerArray":
            return bytes(self.typestore.serialize_cdr(msg, type_name))
        return msg


@pytest.fixture(params=["rosbags", "rclpy", "serialized"])
def msgs(request: pytest.FixtureRequest) -> object:
    """Every conversion with rosbags dataclasses, rclpy classes and serialized arrays (drd_msgs_py.marker_cdr)."""
    from rosbags.typesys import Stores, get_typestore

    if request.param == "rclpy":
        pytest.importorskip("visualization_msgs.msg", reason="rclpy message wheels not installed")
        return RclpyMessages()
    store = get_typestore(Stores.ROS2_JAZZY)
    return SerializedMessages(store) if request.param == "serialized" else RosbagsMessages(store)


TET = MeshData(
    np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64),
    np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]], dtype=np.int64),
)
#: A sagging wire's polyline (5 knots, 4 m of sag in the middle) in the message frame.
WIRE = np.array([[0, 0, 30], [25, 0, 27], [50, 0, 26], [75, 0, 27], [100, 0, 30]], dtype=np.float64)


def _world(msgs: Any) -> Any:
    yaw = math.radians(30)
    return markers_from_obstacles(
        [
            ("box/1", BoxData((2, 3, 4)), PoseData((1, 2, 3), (0, 0, math.sin(yaw / 2), math.cos(yaw / 2)))),
            ("ball/2", SphereData(1.5), PoseData((5, 5, 5))),
            ("nofly/3", CylinderData(50.0, 200.0), PoseData((300, 0, 100))),
            ("mesh/4", TET, PoseData((-5, 0, 0))),
            ("wire/5", LineStripData(WIRE, 0.05), PoseData()),
        ],
        frame_id=FRAME,
        stamp=(12, 5),
        msgs=msgs,
    )


def test_round_trip_gives_the_same_shapes(msgs: Any) -> None:
    update = obstacle_update(_world(msgs), frame_id=FRAME)
    assert update.operations[0] == ("clear", "")
    assert [k for op, k in update.operations[1:]] == ["box/1", "ball/2", "nofly/3", "mesh/4", "wire/5"]
    obs = update.apply({})
    box = obs["box/1"]
    assert box.shape == BoxData((2.0, 3.0, 4.0))
    assert box.kind == "CUBE"
    assert box.label == "marker 1 (box/1)"
    np.testing.assert_allclose(box.pose.position, (1, 2, 3))
    np.testing.assert_allclose(box.pose.quaternion_xyzw, (0, 0, math.sin(math.radians(15)), math.cos(math.radians(15))))
    assert obs["ball/2"].shape == SphereData(1.5)
    assert obs["nofly/3"].shape == CylinderData(50.0, 200.0)
    mesh = obs["mesh/4"].shape
    assert isinstance(mesh, MeshData)
    assert mesh.faces.shape == (4, 3)
    assert obs["mesh/4"].points == 12
    np.testing.assert_array_equal(mesh.vertices, TET.vertices[TET.faces.reshape(-1)])
    wire = obs["wire/5"].shape
    assert isinstance(wire, LineStripData)
    assert wire.diameter == pytest.approx(0.05)
    np.testing.assert_allclose(wire.points, WIRE, atol=1e-12)
    assert obs["wire/5"].pose == PoseData()
    assert obs["wire/5"].points == 5


def test_delete_and_delete_all_apply_in_order(msgs: Any) -> None:
    first = obstacle_update(_world(msgs), frame_id=FRAME).apply({})
    header = msgs("std_msgs/msg/Header", frame_id=FRAME)
    delete = msgs("visualization_msgs/msg/Marker", header=header, ns="box", id=1, action=2)
    after = obstacle_update(msgs("visualization_msgs/msg/MarkerArray", markers=[delete]), frame_id=FRAME).apply(first)
    assert "box/1" not in after
    assert "ball/2" in after
    assert "box/1" in first
    clear = msgs("visualization_msgs/msg/Marker", header=header, action=3)
    assert (
        obstacle_update(msgs("visualization_msgs/msg/MarkerArray", markers=[clear]), frame_id=FRAME).apply(first) == {}
    )


def _one(msgs: Any, **fields: Any) -> Any:
    base: dict[str, Any] = {
        "header": msgs("std_msgs/msg/Header", frame_id=FRAME),
        "ns": "o",
        "id": 1,
        "type": CUBE,
        "action": 0,
        "pose": msgs("geometry_msgs/msg/Pose", orientation=msgs("geometry_msgs/msg/Quaternion", w=1.0)),
        "scale": msgs("geometry_msgs/msg/Vector3", x=1.0, y=1.0, z=1.0),
    }
    base.update(fields)
    return msgs("visualization_msgs/msg/MarkerArray", markers=[msgs("visualization_msgs/msg/Marker", **base)])


def _build(msgs: Any, value: Any) -> Any:
    """(type, {field: value-or-(type, {...})}) -> a message; anything else unchanged."""
    if isinstance(value, tuple):
        return msgs(value[0], **{k: _build(msgs, v) for k, v in value[1].items()})
    return value


@pytest.mark.parametrize(
    ("fields", "words"),
    [
        ({"type": 0}, "unsupported marker type ARROW"),
        ({"type": 10}, "MESH_RESOURCE"),
        ({"action": 7}, "unsupported marker action 7"),
        ({"scale": ("geometry_msgs/msg/Vector3", {"x": 0.0, "y": 1.0, "z": 1.0})}, "zero-size"),
        ({"scale": ("geometry_msgs/msg/Vector3", {"x": -1.0, "y": 1.0, "z": 1.0})}, "> 0"),
        ({"scale": ("geometry_msgs/msg/Vector3", {"x": float("nan"), "y": 1.0, "z": 1.0})}, "finite"),
        ({"type": 2, "scale": ("geometry_msgs/msg/Vector3", {"x": 1.0, "y": 2.0, "z": 1.0})}, "ellipsoids"),
        ({"type": 3, "scale": ("geometry_msgs/msg/Vector3", {"x": 1.0, "y": 2.0, "z": 1.0})}, "elliptic"),
        (
            {
                "pose": (
                    "geometry_msgs/msg/Pose",
                    {"orientation": ("geometry_msgs/msg/Quaternion", {"w": 0.0})},
                )
            },
            "unit quaternion",
        ),
        (
            {
                "pose": (
                    "geometry_msgs/msg/Pose",
                    {"orientation": ("geometry_msgs/msg/Quaternion", {"w": 2.0})},
                )
            },
            "unit quaternion",
        ),
        ({"header": ("std_msgs/msg/Header", {"frame_id": "odom"})}, "frame 'odom'"),
        ({"type": LINE_STRIP}, "at least 2 points"),
        ({"type": 11}, "3k points"),
    ],
)
def test_malformed_markers_are_refused(msgs: Any, fields: dict[str, Any], words: str) -> None:
    built = {k: _build(msgs, v) for k, v in fields.items()}
    with pytest.raises(MessageError, match=words):
        obstacle_update(_one(msgs, **built), frame_id=FRAME)


def test_nan_point_and_repeated_points_are_refused(msgs: Any) -> None:
    p = msgs("geometry_msgs/msg/Point", x=1.0, y=2.0, z=3.0)
    with pytest.raises(MessageError, match="zero-length"):
        obstacle_update(_one(msgs, type=LINE_STRIP, points=[p, p]), frame_id=FRAME)
    bad = msgs("geometry_msgs/msg/Point", x=float("nan"), y=0.0, z=0.0)
    with pytest.raises(MessageError, match="point 1"):
        obstacle_update(_one(msgs, type=LINE_STRIP, points=[p, bad]), frame_id=FRAME)


def test_not_a_marker_array_is_refused(msgs: Any) -> None:
    with pytest.raises(MessageError, match="MarkerArray"):
        obstacle_update(msgs("std_msgs/msg/String", data="x"), frame_id=FRAME)


# --------------------------------------------------------------------------------------------------
# Frames first, and map limits (issue 19)


def test_a_lone_deleteall_in_a_foreign_frame_is_refused(msgs: Any) -> None:
    first = obstacle_update(_world(msgs), frame_id=FRAME).apply({})
    clear = msgs("visualization_msgs/msg/Marker", header=msgs("std_msgs/msg/Header", frame_id="odom"), action=3)
    with pytest.raises(MessageError, match=r"marker 0 .* frame 'odom'; the planner works in 'map'"):
        obstacle_update(msgs("visualization_msgs/msg/MarkerArray", markers=[clear]), frame_id=FRAME)
    assert len(first) == 5


def _cubes(msgs: Any, count: int, *, ns: str = "box") -> Any:
    return markers_from_obstacles(
        [(f"{ns}/{k}", BoxData((1, 1, 1)), PoseData((3.0 * k, 0, 0))) for k in range(count)],
        frame_id=FRAME,
        msgs=msgs,
        delete_all_first=False,
    )


def test_arrays_over_a_limit_are_refused_before_any_shape_is_built(msgs: Any, monkeypatch: pytest.MonkeyPatch) -> None:
    def no_shapes(*_: Any) -> None:
        raise AssertionError("a shape was built before the limits were checked")

    monkeypatch.setattr(obstacles_module, "_obstacle", no_shapes)
    small = MessageLimits(max_markers=4, max_line_points=4, max_mesh_triangles=3)
    with pytest.raises(MessageError) as info:
        obstacle_update(_cubes(msgs, 5), frame_id=FRAME, limits=small)
    assert str(info.value) == "the MarkerArray has 5 markers, over the limit max_markers = 4 (parameter max_markers)"
    wire = markers_from_obstacles(
        [
            (
                "wire/0",
                LineStripData(np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0], [4, 0, 0]], float), 0.1),
                PoseData(),
            )
        ],
        frame_id=FRAME,
        msgs=msgs,
    )
    with pytest.raises(MessageError, match=r"5 LINE_STRIP points, over the limit max_line_points = 4 \("):
        obstacle_update(wire, frame_id=FRAME, limits=small)
    rng = np.random.default_rng(1)
    mesh = MeshData(rng.random((12, 3)), np.arange(12).reshape(4, 3))
    meshes = markers_from_obstacles([("mesh/0", mesh, PoseData())], frame_id=FRAME, msgs=msgs)
    with pytest.raises(MessageError, match="4 TRIANGLE_LIST triangles, over the limit max_mesh_triangles = 3"):
        obstacle_update(meshes, frame_id=FRAME, limits=small)


def test_a_map_growing_over_a_limit_is_refused_and_kept(msgs: Any) -> None:
    limits = MessageLimits(max_markers=6, max_mesh_triangles=5)
    current = obstacle_update(_cubes(msgs, 4), frame_id=FRAME, limits=limits).apply({})
    more = obstacle_update(_cubes(msgs, 3, ns="more"), frame_id=FRAME, limits=limits)
    with pytest.raises(MessageError, match="the obstacle map would have 7 obstacles, over the limit max_markers = 6"):
        more.apply(current)
    assert len(current) == 4
    assert len(obstacle_update(_cubes(msgs, 2, ns="more"), frame_id=FRAME, limits=limits).apply(current)) == 6
    one = markers_from_obstacles([("mesh/0", TET, PoseData())], frame_id=FRAME, msgs=msgs, delete_all_first=False)
    two = markers_from_obstacles([("mesh/1", TET, PoseData())], frame_id=FRAME, msgs=msgs, delete_all_first=False)
    with_mesh = obstacle_update(one, frame_id=FRAME, limits=limits).apply({})
    assert with_mesh["mesh/0"].points == 12
    with pytest.raises(MessageError, match="8 TRIANGLE_LIST triangles, over the limit max_mesh_triangles = 5"):
        obstacle_update(two, frame_id=FRAME, limits=limits).apply(with_mesh)
    replaced = obstacle_update(one, frame_id=FRAME, limits=limits).apply(with_mesh)  # same key: still 4
    assert set(replaced) == {"mesh/0"}


def test_marker_strings_are_bounded_and_never_quoted_whole(msgs: Any) -> None:
    """Issue 33 item 4: twelve markers with 8 MB namespaces were kept as map keys (RSS +290 MiB)."""
    long_ns = "n" * 300
    with pytest.raises(MessageError, match=r"marker 0: its ns has 300 characters .*at most 256") as info:
        obstacle_update(_cubes(msgs, 1, ns=long_ns), frame_id=FRAME)
    assert len(str(info.value)) < 300
    if isinstance(msgs, SerializedMessages):
        pytest.skip("edits the markers of an array (the serialized strings: tests/msgs/test_marker_cdr.py)")
    array = _cubes(msgs, 3)
    for marker in array.markers:
        marker.text = "t" * 1000
    small = MessageLimits(max_message_bytes=2500)
    with pytest.raises(MessageError, match=r"strings .* reach \d+ characters by marker 2, over the limit "):
        obstacle_update(array, frame_id=FRAME, limits=small)
    assert len(obstacle_update(array, frame_id=FRAME).obstacles) == 3  # within the default limit
    array.markers[0].header.frame_id = "f" * 100_000
    with pytest.raises(MessageError, match="frame") as info:
        obstacle_update(array, frame_id=FRAME)
    assert len(str(info.value)) < 300


def test_a_marker_equal_to_the_held_obstacle_gives_the_held_object(msgs: Any) -> None:
    """Issue 33 item 5: every shape kind, given again unchanged, is the held obstacle; any change is a new one."""
    held = obstacle_update(_world(msgs), frame_id=FRAME).apply({})
    again = obstacle_update(_world(msgs), frame_id=FRAME, held=held).apply(held)
    assert all(again[key] is held[key] for key in held)
    assert all(same_obstacle(again[key], obstacle_update(_world(msgs), frame_id=FRAME).obstacles[key]) for key in held)
    bent = WIRE.copy()
    bent[2, 2] += 1e-9
    changed = markers_from_obstacles(
        [
            ("wire/5", LineStripData(bent, 0.05), PoseData()),
            ("mesh/4", TET, PoseData((-5, 0, 1e-9))),
            ("box/1", BoxData((2, 3, 4.5)), held["box/1"].pose),
            ("ball/2", SphereData(1.5), PoseData((5, 5, 5))),
        ],
        frame_id=FRAME,
        msgs=msgs,
        delete_all_first=False,
    )
    update = obstacle_update(changed, frame_id=FRAME, held=held).obstacles
    assert [key for key in update if update[key] is held[key]] == ["ball/2"]
    assert not any(same_obstacle(update[key], held[key]) for key in ("wire/5", "mesh/4", "box/1"))
