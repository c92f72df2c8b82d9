"""What the node sends for each plan, as serialized bytes: the Path and JointTrajectory in bulk, the diagnostics.

A Path of K poses built as rclpy message objects costs Python work per pose twice: K PoseStamped
(each with a Pose, Point and Quaternion) are made, and rclpy converts each one to C when it is
published (together about 28 ms for the 679 poses of a ``heli_lines`` plan, 3 ms for a 103-point arm
trajectory). Serialized, the same message is a fixed header followed by one record per pose whose
layout is the same from the second record on, so numpy writes all of them at once (about 0.15 ms
for those 679 poses). An rclpy publisher sends ``bytes`` as they are (``Publisher.publish``); a bag
writer stores them. The check log and the summaries (``diagnostic_msgs/DiagnosticArray``) are written
the same way from :class:`~drd_msgs_py.plans.StatusFields`: as message objects they cost about 0.6 ms a
plan, in the planning thread right after the Path.

Encoding: ROS 2's serialized message, plain little-endian CDR (XCDR1) after the 4-byte encapsulation
header ``00 01 00 00``. Numbers are aligned to their size (float64 to 8 bytes) counted from the end
of that header; a string is a uint32 length (its NUL included), its UTF-8 bytes and a NUL; a
sequence is a uint32 count and its elements. Padding bytes are zero: the bytes equal rosbags'
``serialize_cdr`` of the message objects of :mod:`drd_msgs_py.plans` (rmw_fastrtps leaves padding
bytes unset, so its own bytes decode to the same message but may differ there).
"""

from __future__ import annotations

import struct
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from drd_msgs_py.plans import StatusFields, path_poses, trajectory_positions, trajectory_times

__all__ = ["ENCAPSULATION", "diagnostic_array_cdr", "joint_trajectory_cdr", "path_cdr"]

#: Encapsulation header of little-endian plain CDR (what ROS 2 middlewares write and read).
ENCAPSULATION = b"\x00\x01\x00\x00"
#: Bytes of one ``JointTrajectoryPoint`` after its positions: empty velocities, accelerations and
#: effort (three uint32 counts of 0), then ``time_from_start`` (int32 sec, uint32 nanosec).
_POINT_TAIL = 20


def _pad(offset: int, alignment: int) -> int:
    """Zero bytes to add at ``offset`` so that the next value starts a multiple of ``alignment``."""
    return -offset % alignment


class _Writer:
    """A CDR buffer: values appended at their alignment, counted from after the encapsulation header."""

    def __init__(self) -> None:
        self._buffer = bytearray(ENCAPSULATION)

    @property
    def offset(self) -> int:
        """Bytes written after the encapsulation header."""
        return len(self._buffer) - len(ENCAPSULATION)

    def align(self, alignment: int) -> None:
        """Pad with zeros to a multiple of ``alignment`` bytes."""
        self._buffer += bytes(_pad(self.offset, alignment))

    def uint32(self, value: int) -> None:
        """A uint32 (a count or a length), aligned to 4."""
        self.align(4)
        self._buffer += struct.pack("<I", value)

    def octet(self, value: int) -> None:
        """One byte (alignment 1)."""
        self._buffer.append(value)

    def raw(self, data: bytes) -> None:
        """Bytes as they are (already laid out for this offset)."""
        self._buffer += data

    def string(self, text: str) -> None:
        """A string: uint32 length with the NUL, UTF-8 bytes, NUL."""
        self.raw(string_bytes(text, self.offset))

    def records(
        self, prefix: bytes, body: npt.NDArray[np.float64], suffix: npt.NDArray[np.uint8] | None = None
    ) -> None:
        """K records: ``prefix``, zeros to 8-byte alignment, a (K, W) ``body`` row as float64, a (K, S) ``suffix`` row.

        ``prefix`` must hold only values aligned to at most 4 bytes and S be a multiple of 4, and the
        records start 4-aligned. Every record then ends S bytes past a multiple of 8, so the second
        and later records have one layout and are written as one (K - 1, size) block; only the
        first record's padding may differ. (A body of width 0 is an empty float64 sequence: no
        padding, as CDR writes nothing for it.)
        """
        rows, width = body.shape
        tail = np.zeros((rows, 0), dtype=np.uint8) if suffix is None else suffix
        if rows == 0:
            return
        if self.offset % 4 or tail.shape[1] % 4:
            raise ValueError("records start 4-aligned and their suffix is a multiple of 4 bytes")
        data = np.ascontiguousarray(body, dtype="<f8").view(np.uint8).reshape(rows, 8 * width)
        self.raw(self._record(prefix, data[0], tail[0]))
        if rows > 1:
            pad = _pad(self.offset + len(prefix), 8) if width else 0
            block = np.zeros((rows - 1, len(prefix) + pad + 8 * width + tail.shape[1]), dtype=np.uint8)
            block[:, : len(prefix)] = np.frombuffer(prefix, dtype=np.uint8)
            start = len(prefix) + pad
            block[:, start : start + 8 * width] = data[1:]
            block[:, start + 8 * width :] = tail[1:]
            self.raw(block.tobytes())

    def _record(self, prefix: bytes, body: npt.NDArray[np.uint8], suffix: npt.NDArray[np.uint8]) -> bytes:
        """One record at the current offset (see :meth:`records`)."""
        pad = _pad(self.offset + len(prefix), 8) if body.size else 0
        return prefix + bytes(pad) + body.tobytes() + suffix.tobytes()

    def bytes(self) -> bytes:
        """The serialized message."""
        return bytes(self._buffer)


def string_bytes(text: str, offset: int) -> bytes:
    """A CDR string written at ``offset``: padding to 4, uint32 length with the NUL, UTF-8 bytes, NUL."""
    data = text.encode("utf-8") + b"\x00"
    return bytes(_pad(offset, 4)) + struct.pack("<I", len(data)) + data


def _header_bytes(frame_id: str, stamp: tuple[int, int]) -> bytes:
    """A ``std_msgs/Header`` (int32 sec, uint32 nanosec, frame_id) starting 4-aligned (8 bytes, then the string)."""
    return struct.pack("<iI", int(stamp[0]), int(stamp[1])) + string_bytes(frame_id, 8)


def path_cdr(states: npt.ArrayLike, *, frame_id: str, stamp: tuple[int, int] = (0, 0)) -> bytes:
    """``nav_msgs/Path`` through (K, >= 3) states as serialized bytes (the message of ``path_message``).

    Column 3 (if present) is the heading in radians; every pose carries the Path's header. Each pose
    is one record: its header (``frame_id`` and ``stamp`` (sec, nanosec)), zeros to 8 bytes, then
    x, y, z (m) and the quaternion x, y, z, w as float64.

    Raises:
        ValueError: ``states`` is not (K, >= 3).
    """
    poses = path_poses(states)
    head = _header_bytes(frame_id, stamp)
    out = _Writer()
    out.raw(head)
    out.uint32(len(poses))
    out.records(head, poses)
    return out.bytes()


def joint_trajectory_cdr(
    joint_names: Sequence[str],
    positions: npt.ArrayLike,
    *,
    frame_id: str,
    stamp: tuple[int, int] = (0, 0),
    seconds_per_point: float = 1.0,
) -> bytes:
    """``trajectory_msgs/JointTrajectory`` through (K, J) joint positions (radians), evenly timed, as bytes.

    The message of :func:`~drd_msgs_py.plans.joint_trajectory_message`: point k at k *
    ``seconds_per_point`` s, with positions only (velocities, accelerations and effort empty).

    Raises:
        ValueError: ``positions`` is not (K, ``len(joint_names)``).
    """
    q = trajectory_positions(joint_names, positions)
    count, joints = q.shape
    out = _Writer()
    out.raw(_header_bytes(frame_id, stamp))
    out.uint32(len(joint_names))
    for name in joint_names:
        out.string(name)
    out.uint32(count)
    tails = np.zeros((count, _POINT_TAIL // 4), dtype="<u4")
    times = trajectory_times(count, seconds_per_point)
    tails[:, 3] = times[:, 0].astype("<i4").view("<u4")
    tails[:, 4] = times[:, 1]
    out.records(struct.pack("<I", joints), q, tails.view(np.uint8).reshape(count, _POINT_TAIL))
    return out.bytes()


def diagnostic_array_cdr(statuses: Sequence[StatusFields], *, stamp: tuple[int, int] = (0, 0)) -> bytes:
    """``diagnostic_msgs/DiagnosticArray`` of ``statuses`` (header frame empty) as serialized bytes.

    The message of :func:`~drd_msgs_py.plans.edge_checks_message` (``check_statuses``) or of a
    summary (``diagnostics_message([summary_status(...)])``): each status is its level byte, name,
    message, hardware_id and key/value strings.
    """
    out = _Writer()
    out.raw(_header_bytes("", stamp))
    out.uint32(len(statuses))
    for status in statuses:
        out.octet(status.level)
        out.string(status.name)
        out.string(status.message)
        out.string(status.hardware_id)
        out.uint32(len(status.values))
        for key, value in status.values:
            out.string(key)
            out.string(value)
    return out.bytes()
