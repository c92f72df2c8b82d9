"""A serialized ``visualization_msgs/MarkerArray`` read in one pass: the fields the obstacle map uses, per marker.

rclpy turns a received MarkerArray into Python objects field by field: for 100 000 cubes that is about 15 s
of the subscriber's CPU (rosbags' ``deserialize_cdr``: about 10 s), before any marker is looked at. A node
that subscribes to the array raw (``create_subscription(..., raw=True)``) gets its serialized bytes instead;
:func:`read_marker_array` walks them once and keeps, per marker, only what
:func:`drd_msgs_py.obstacles.obstacle_update` reads (about 3 us a cube):

- ``ns``, ``id``, ``type``, ``action``, the header's ``frame_id``, ``text`` and ``mesh_resource``;
- ``values``: the pose (position x, y, z, quaternion x, y, z, w) then the scale (x, y, z), 10 floats;
- ``points``: the (K, 3) points, float64 (a copy: a marker holds no reference to the message's buffer);
- ``content``: the byte order (``<`` or ``>``), then the bytes of ``type``, ``pose``, ``scale`` and
  ``points`` as they arrived. Two markers with the same content make the same obstacle (the same numbers
  bit for bit), so a consumer that holds an obstacle built from equal content can keep it without reading
  or validating the marker again.

Encoding (ROS 2's serialized message; see :mod:`drd_msgs_py.cdr`): plain CDR (XCDR1), little- or big-endian
as the 4-byte encapsulation header says; numbers aligned to their size counted from the end of that header;
a string is a uint32 length (its NUL included) and its bytes; a sequence a uint32 count and its elements.
Padding bytes are skipped, never read (rmw_fastrtps leaves them unset). Fields of Jazzy's ``Marker`` in
order: header (stamp, frame_id), ns, id, type, action, pose, scale, color, lifetime, frame_locked, points,
colors, texture_resource, texture (``sensor_msgs/CompressedImage``), uv_coordinates, text, mesh_resource,
mesh_file (``visualization_msgs/MeshFile``), mesh_use_embedded_materials.
"""

from __future__ import annotations

import struct
from typing import NamedTuple

import numpy as np

from drd_msgs_py.arrays import BoolArray, FloatArray
from drd_msgs_py.exceptions import MessageError
from drd_msgs_py.limits import DEFAULT_LIMITS, MessageLimits

__all__ = ["CdrMarker", "MarkerArrayReader", "read_marker_array"]

#: Encapsulation identifiers (first two bytes) of plain CDR, big- and little-endian.
_ENDIAN = {b"\x00\x00": ">", b"\x00\x01": "<"}
#: Bytes of ``pose`` (7 float64) and ``scale`` (3 float64), contiguous from an 8-aligned offset.
_POSE_SCALE = 80
#: Bytes of ``color`` (4 float32), ``lifetime`` (int32, uint32) and ``frame_locked`` (bool) after ``scale``.
_COLOR_LIFETIME_LOCKED = 16 + 8 + 1

#: The fields after ``points`` up to the last bool, with their element sizes in bytes: a sequence or string is
#: a 4-aligned uint32 count then that many elements (none is wider than 4 bytes: no padding); -1 is a stamp.
_TAIL = (
    ("colors", 16),
    ("texture_resource", 1),
    ("texture stamp", -1),
    ("texture frame_id", 1),
    ("texture format", 1),
    ("texture data", 1),
    ("uv_coordinates", 8),
    ("text", 1),
    ("mesh_resource", 1),
    ("mesh_file filename", 1),
    ("mesh_file data", 1),
)
#: The strings of :data:`_TAIL` that a :class:`CdrMarker` keeps.
_KEPT_STRINGS = ("text", "mesh_resource")


#: The points of a marker without any (shared, read-only).
_NO_POINTS = np.zeros((0, 3))
_NO_POINTS.flags.writeable = False


class CdrMarker(NamedTuple):
    """The fields of one serialized marker that the obstacle map reads (see the module docstring).

    Attributes:
        ns, id, type, action: the marker's fields.
        frame_id: its header's frame.
        values: pose position (x, y, z) metres, quaternion (x, y, z, w), scale (x, y, z) metres: 10 floats.
        points: (K, 3) float64 points (marker frame, metres), read-only.
        content: the byte order, then the serialized ``type``, ``pose``, ``scale`` and ``points`` (equal: equal
        obstacle).
        text, mesh_resource: its strings of those names (counted against ``max_message_bytes``).
    """

    ns: str
    id: int
    type: int
    action: int
    frame_id: str
    values: tuple[float, ...]
    points: FloatArray
    content: bytes
    text: str = ""
    mesh_resource: str = ""


class _Reader:
    """A position in a CDR buffer; every read checks that the bytes are there (one method per marker: speed)."""

    def __init__(self, data: bytes, endian: str) -> None:
        self.data = data
        self.pos = 4  # after the encapsulation header; alignment counts from here
        self._u32 = struct.Struct(endian + "I").unpack_from
        self._3i = struct.Struct(endian + "3i").unpack_from
        self._10d = struct.Struct(endian + "10d").unpack_from
        self.point_dtype = np.dtype(endian + "f8")
        self.tag = endian.encode()  # starts every content: equal bytes in another byte order are other numbers

    def _fail(self, pos: int, what: str) -> MessageError:
        return MessageError(f"serialized MarkerArray ends inside {what} (byte {pos} of {len(self.data)})")

    def uint32(self, what: str) -> int:
        """The next uint32 (aligned)."""
        pos = self.pos + (-self.pos) % 4  # 4 divides the header's length: same alignment as from after it
        if pos + 4 > len(self.data):
            raise self._fail(pos, what)
        self.pos = pos + 4
        return int(self._u32(self.data, pos)[0])

    def marker(self, i: int) -> CdrMarker:
        """The next marker (``i``: its index, for error texts).

        Strings and sequences are skipped or read in line, in field order (see the module docstring): each
        field is a uint32 count or length at a 4-aligned offset, then its bytes (8-aligned for points).
        """
        data, u32, end = self.data, self._u32, len(self.data)
        pos = self.pos + 8 + (-self.pos) % 4  # header stamp
        strings: list[str] = []
        field = "header frame_id"
        try:
            for field in ("header frame_id", "ns"):
                pos += (-pos) % 4
                (size,) = u32(data, pos)
                if pos + 4 + size > end:
                    raise self._fail(pos, f"marker {i} {field}")
                strings.append(data[pos + 4 : pos + 3 + size].decode("utf-8") if size > 1 else "")
                pos += 4 + size
            field = "id, type, action"
            first = pos + (-pos) % 4
            ident, kind, action = self._3i(data, first)
            field = "pose and scale"
            pose = first + 12 + (4 - (first + 12)) % 8  # 8-aligned counted from after the header
            values = self._10d(data, pose)
            field = "points"
            pos = pose + _POSE_SCALE + _COLOR_LIFETIME_LOCKED
            pos += (-pos) % 4
            (count,) = u32(data, pos)
            start = pos + 4 + ((4 - (pos + 4)) % 8 if count else 0)
            pos = start + 24 * count
            if pos > end:
                raise self._fail(start, f"marker {i} points")
            points = (
                np.frombuffer(data, self.point_dtype, 3 * count, start).reshape(count, 3).astype(np.float64)
                if count
                else _NO_POINTS
            )  # a copy: a kept marker must not keep its message's buffer alive
            for field, size_of in _TAIL:
                pos += (-pos) % 4
                if size_of < 0:
                    pos += 8
                    continue
                (size,) = u32(data, pos)
                if pos + 4 + size * size_of > end:
                    raise self._fail(pos, f"marker {i} {field}")
                if field in _KEPT_STRINGS:
                    strings.append(data[pos + 4 : pos + 3 + size].decode("utf-8") if size > 1 else "")
                pos += 4 + size * size_of
            field = "mesh_use_embedded_materials"
            if pos + 1 > end:
                raise self._fail(pos, f"marker {i} {field}")
            self.pos = pos + 1
        except struct.error:
            raise self._fail(pos, f"marker {i} {field}") from None
        except UnicodeDecodeError:
            raise MessageError(f"marker {i} {field} is not UTF-8") from None
        content = self.tag + data[first + 4 : first + 8] + data[pose : pose + _POSE_SCALE]
        content += data[start : start + 24 * count]
        frame_id, ns, text, mesh_resource = strings
        return CdrMarker(ns, ident, kind, action, frame_id, values, points, content, text, mesh_resource)


def _open(data: bytes, limits: MessageLimits) -> tuple[_Reader, int]:
    """A reader at the first marker of ``data`` and the marker count (checked against ``max_markers``)."""
    endian = _ENDIAN.get(data[:2])
    if endian is None or len(data) < 8:
        raise MessageError(f"not a serialized MarkerArray (plain CDR): header {data[:4].hex() or 'missing'}")
    reader = _Reader(data, endian)
    count = reader.uint32("the MarkerArray's marker count")
    if count > limits.max_markers:
        raise MessageError(limits.refusal("max_markers", f"the MarkerArray has {count} markers"))
    return reader, count


def read_marker_array(data: bytes | bytearray | memoryview, limits: MessageLimits = DEFAULT_LIMITS) -> list[CdrMarker]:
    """The markers of a serialized ``visualization_msgs/MarkerArray`` (see the module docstring).

    The marker count is checked against ``limits.max_markers`` before any marker is read.

    Raises:
        MessageError: not plain CDR, bytes that end before the array does, a string that is not UTF-8, more
            markers than ``max_markers``.
    """
    reader, count = _open(bytes(data), limits)
    return [reader.marker(i) for i in range(count)]


class MarkerArrayReader:
    """Reads serialized MarkerArrays one after the other, reading again only the markers whose bytes changed.

    A latched obstacle topic sends the whole map each time, mostly the bytes it sent before. The reader keeps
    the last array it read: its bytes, its markers and each marker's byte range ``[start, end)``. Reading a
    marker depends only on its start offset (alignment counts from the buffer's start) and on the bytes of
    its range, so a marker of the new array that starts where a kept marker started, over a range whose bytes
    are all unchanged (and within the same encapsulation header), reads as the kept marker: it is that
    :class:`CdrMarker`, and so are the kept markers after it while their bytes are unchanged. Changed bytes
    are found by comparing the two buffers (numpy, C speed); the markers around them are read as
    :func:`read_marker_array` reads them. Memory: the last array's bytes and markers (about 0.7 KB a cube).
    """

    def __init__(self) -> None:
        self._data = b""
        self._markers: list[CdrMarker] = []
        self._starts = np.zeros(0, dtype=np.int64)
        self._ends = np.zeros(0, dtype=np.int64)

    def read(self, data: bytes | bytearray | memoryview, limits: MessageLimits = DEFAULT_LIMITS) -> list[CdrMarker]:
        """The markers of ``data`` (equal to :func:`read_marker_array`'s; raises as it does, keeping the last array)."""
        data = bytes(data)
        reader, count = _open(data, limits)
        clean = self._clean(data)
        dirty = np.flatnonzero(~clean)
        markers: list[CdrMarker] = []
        starts: list[int] = []
        ends: list[int] = []
        while len(markers) < count:
            k = int(np.searchsorted(self._starts, reader.pos))
            if k < len(clean) and clean[k] and self._starts[k] == reader.pos:
                after = int(np.searchsorted(dirty, k))
                stop = min(int(dirty[after]) if after < len(dirty) else len(clean), k + count - len(markers))
                markers += self._markers[k:stop]
                starts += self._starts[k:stop].tolist()
                ends += self._ends[k:stop].tolist()
                reader.pos = int(self._ends[stop - 1])
                continue
            starts.append(reader.pos)
            markers.append(reader.marker(len(markers)))
            ends.append(reader.pos)
        self._data, self._markers = data, markers
        self._starts, self._ends = np.array(starts, dtype=np.int64), np.array(ends, dtype=np.int64)
        return markers

    def _clean(self, data: bytes) -> BoolArray:
        """(K,) whether each kept marker's byte range is unchanged in ``data`` (all False: another header)."""
        if not self._markers or data[:4] != self._data[:4]:
            return np.zeros(len(self._markers), dtype=bool)
        common = min(len(data), len(self._data))
        old, new = np.frombuffer(self._data, np.uint8, common), np.frombuffer(data, np.uint8, common)
        changed = np.flatnonzero(old != new)
        inside = np.searchsorted(changed, self._ends) - np.searchsorted(changed, self._starts)
        return (inside == 0) & (self._ends <= common)  # type: ignore[no-any-return]
