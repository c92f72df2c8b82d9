"""The one-pass reader of serialized MarkerArrays: the fields rosbags and rclpy decode; malformed buffers refused."""

from __future__ import annotations

import dataclasses
import struct
from typing import Any

import numpy as np
import pytest

from drd_msgs_py.bags import jazzy_typestore
from drd_msgs_py.exceptions import MessageError
from drd_msgs_py.factory import RosbagsMessages
from drd_msgs_py.limits import MessageLimits
from drd_msgs_py.marker_cdr import CdrMarker, MarkerArrayReader, read_marker_array
from drd_msgs_py.obstacles import obstacle_update

ARRAY = "visualization_msgs/msg/MarkerArray"


def _marker(rb: RosbagsMessages, k: int, **fields: Any) -> Any:
    """Marker ``k``: strings and sequences of lengths that shift every later field's alignment."""
    base: dict[str, Any] = {
        "header": rb("std_msgs/msg/Header", frame_id="map" + "x" * (k % 3)),
        "ns": "n" * (k % 5),
        "id": k - 2,
        "type": 4 if k % 2 else 1,
        "action": 0,
        "pose": rb(
            "geometry_msgs/msg/Pose",
            position=rb("geometry_msgs/msg/Point", x=1.5 * k, y=-2.0, z=0.25 * k),
            orientation=rb("geometry_msgs/msg/Quaternion", z=0.6, w=0.8),
        ),
        "scale": rb("geometry_msgs/msg/Vector3", x=0.1 + k, y=0.2, z=0.3),
        "points": [rb("geometry_msgs/msg/Point", x=float(i), y=float(k), z=-float(i)) for i in range(k % 4)],
        "colors": [rb("std_msgs/msg/ColorRGBA", r=0.5)] * (k % 3),
        "texture_resource": "t" * (k % 2),
        "texture": rb(
            "sensor_msgs/msg/CompressedImage",
            header=rb("std_msgs/msg/Header", frame_id="c" * (k % 4)),
            format="png"[: k % 4],
            data=np.arange(k % 5, dtype=np.uint8),
        ),
        "uv_coordinates": [rb("visualization_msgs/msg/UVCoordinate", u=0.5, v=0.25)] * (k % 2),
        "text": "héllo"[: k % 6],
        "mesh_resource": "package://m"[: k % 7],
        "mesh_file": rb("visualization_msgs/msg/MeshFile", filename="f" * (k % 3), data=np.ones(k % 3, np.uint8)),
        "mesh_use_embedded_materials": bool(k % 2),
    }
    base.update(fields)
    return rb("visualization_msgs/msg/Marker", **base)


@pytest.fixture(scope="module")
def rb() -> RosbagsMessages:
    return RosbagsMessages(jazzy_typestore())


def _serialized(rb: RosbagsMessages, markers: list[Any], *, little_endian: bool = True) -> bytes:
    msg = rb(ARRAY, markers=markers)
    return bytes(rb.typestore.serialize_cdr(msg, ARRAY, little_endian=little_endian))


def _expected(marker: Any) -> tuple[Any, ...]:
    p, q, s = marker.pose.position, marker.pose.orientation, marker.scale
    values = (p.x, p.y, p.z, q.x, q.y, q.z, q.w, s.x, s.y, s.z)
    points = [[pt.x, pt.y, pt.z] for pt in marker.points]
    fields = (marker.ns, marker.id, marker.type, marker.action, marker.header.frame_id, marker.text)
    return (*fields, marker.mesh_resource, values, points)


@pytest.mark.parametrize("little_endian", [True, False])
def test_every_marker_reads_as_rosbags_decodes_it(rb: RosbagsMessages, little_endian: bool) -> None:
    markers = [_marker(rb, k) for k in range(24)]
    data = _serialized(rb, markers, little_endian=little_endian)
    decoded = rb.typestore.deserialize_cdr(data, ARRAY).markers
    got = read_marker_array(data)
    assert len(got) == 24
    for read, marker in zip(got, decoded, strict=True):
        fields = (read.ns, read.id, read.type, read.action, read.frame_id, read.text, read.mesh_resource)
        assert (*fields, read.values, read.points.tolist()) == _expected(marker)
        assert read.points.shape == (len(marker.points), 3)


def test_rclpy_serialized_bytes_read_the_same(rb: RosbagsMessages) -> None:
    serialization = pytest.importorskip("rclpy.serialization", reason="rclpy not installed")
    from visualization_msgs.msg import MarkerArray

    data = _serialized(rb, [_marker(rb, k) for k in range(12)])
    rclpy_bytes = serialization.serialize_message(serialization.deserialize_message(data, MarkerArray))
    assert [m.values for m in read_marker_array(rclpy_bytes)] == [m.values for m in read_marker_array(data)]


def test_content_is_the_shape_and_pose_only(rb: RosbagsMessages) -> None:
    base = _marker(rb, 3)
    restyled = _marker(rb, 3, text="other", color=rb("std_msgs/msg/ColorRGBA", g=1.0), ns="elsewhere")
    moved = _marker(rb, 3, pose=rb("geometry_msgs/msg/Pose", orientation=rb("geometry_msgs/msg/Quaternion", w=1.0)))
    a, b, c = read_marker_array(_serialized(rb, [base, restyled, moved]))
    assert a.content == b.content
    assert a.content != c.content
    wider = read_marker_array(_serialized(rb, [_marker(rb, 3, scale=rb("geometry_msgs/msg/Vector3", x=9.0))]))
    assert wider[0].content != a.content
    big = read_marker_array(_serialized(rb, [base], little_endian=False))[0]
    # one number, two byte orders: told apart
    assert big.values == a.values
    assert big.content[0] != a.content[0]


def test_every_truncation_is_refused_as_a_message_error(rb: RosbagsMessages) -> None:
    data = _serialized(rb, [_marker(rb, k) for k in range(3)])
    assert len(read_marker_array(data)) == 3
    for end in range(len(data) - 1):  # the last byte (a bool) may be followed by nothing
        with pytest.raises(MessageError):
            read_marker_array(data[:end])


def test_malformed_buffers_are_refused(rb: RosbagsMessages) -> None:
    with pytest.raises(MessageError, match="plain CDR"):
        read_marker_array(b"\x00\x07\x00\x00" + bytes(8))
    huge_count = b"\x00\x01\x00\x00" + (10**6).to_bytes(4, "little")
    with pytest.raises(MessageError, match="1000000 markers, over the limit max_markers = 10"):
        read_marker_array(huge_count, MessageLimits(max_markers=10))
    with pytest.raises(MessageError, match="ends inside marker 0"):
        read_marker_array(huge_count, MessageLimits(max_markers=10**6))
    data = bytearray(_serialized(rb, [_marker(rb, 4, ns="abcd")]))
    at = bytes(data).index(b"abcd")
    data[at] = 0xFF
    with pytest.raises(MessageError, match="marker 0 ns is not UTF-8"):
        read_marker_array(bytes(data))
    point = rb("geometry_msgs/msg/Point", x=12345.5)
    data = bytearray(_serialized(rb, [_marker(rb, 1, points=[point])]))
    start = bytes(data).index(struct.pack("<d", 12345.5))
    count_at = start - 4 if data[start - 4 : start] == b"\x01\x00\x00\x00" else start - 8
    data[count_at : count_at + 4] = (2**31).to_bytes(4, "little")  # a point count far beyond the buffer
    with pytest.raises(MessageError, match="ends inside marker 0 points"):
        read_marker_array(bytes(data))


def test_serialized_strings_count_against_the_message_limit(rb: RosbagsMessages) -> None:
    head = rb("std_msgs/msg/Header", frame_id="map")
    markers = [_marker(rb, 2 * k, header=head, text="t" * 1000, points=[]) for k in range(3)]
    data = _serialized(rb, markers)
    with pytest.raises(MessageError, match=r"strings .* reach \d+ characters by marker 2, over the limit "):
        obstacle_update(data, frame_id="map", limits=MessageLimits(max_message_bytes=2500))
    far = _serialized(rb, [_marker(rb, 0, header=rb("std_msgs/msg/Header", frame_id="f" * 100_000))])
    with pytest.raises(MessageError, match="frame") as info:
        obstacle_update(far, frame_id="map")
    assert len(str(info.value)) < 300


def _fields(marker: CdrMarker) -> tuple[Any, ...]:
    return (*marker[:6], marker.points.tolist(), marker.content, marker.text, marker.mesh_resource)


def test_a_reader_reuses_unchanged_markers_and_reads_as_a_fresh_read(rb: RosbagsMessages) -> None:
    """Seeded edits (move, resize a string, insert, delete, another endianness): equal to reading anew each time."""
    rng = np.random.default_rng(5)
    markers = [_marker(rb, k) for k in range(30)]
    reader = MarkerArrayReader()
    previous: list[CdrMarker] = []
    for step in range(60):
        edit = step % 6
        k = int(rng.integers(len(markers)))
        if edit == 0:  # one marker moved: every other one is the kept object
            pose = rb("geometry_msgs/msg/Pose", position=rb("geometry_msgs/msg/Point", x=float(rng.normal())))
            markers[k] = dataclasses.replace(markers[k], pose=pose)
        elif edit == 1:  # a longer string: every later marker shifts
            markers[k] = _marker(rb, k, ns="s" * int(rng.integers(9)), text="x" * int(rng.integers(5)))
        elif edit == 2:
            markers.insert(k, _marker(rb, int(rng.integers(40))))
        elif edit == 3 and len(markers) > 5:
            del markers[k]
        little = edit != 4
        data = _serialized(rb, markers, little_endian=little)
        got = reader.read(data)
        fresh = read_marker_array(data)
        assert [_fields(m) for m in got] == [_fields(m) for m in fresh], step
        kept = sum(1 for m in got if any(m is p for p in previous))
        if edit == 0 and little and step % 12 != 0:
            assert kept >= len(markers) - 1, (step, kept)
        previous = got
    same = reader.read(data)
    assert all(a is b for a, b in zip(same, previous, strict=True))


def test_a_reader_refusing_an_array_keeps_the_last_one(rb: RosbagsMessages) -> None:
    reader = MarkerArrayReader()
    data = _serialized(rb, [_marker(rb, k) for k in range(6)])
    first = reader.read(data)
    with pytest.raises(MessageError, match="ends inside"):
        reader.read(data[:-9])
    assert all(a is b for a, b in zip(reader.read(data), first, strict=True))
