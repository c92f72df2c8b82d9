"""Obstacles: ``visualization_msgs/MarkerArray`` <-> plain marker shapes with their poses.

Marker semantics (docs/ros-node.md, "Topics, services and actions"):

- CUBE: a box of ``scale`` (x, y, z) metres; SPHERE: a sphere of diameter ``scale.x`` (= y = z);
  CYLINDER: a cylinder along the marker's z with diameter ``scale.x`` (= y) and height ``scale.z``;
- LINE_STRIP: a wire (or any thin body) of diameter ``scale.x`` through ``points`` (given in the marker
  frame; a consumer makes one capsule per segment, so a wire with sag arrives as its polyline);
- TRIANGLE_LIST: a triangle mesh, three ``points`` per triangle (a surface, as FCL treats meshes);
- actions ADD (= MODIFY) replaces the obstacle ``ns/id``, DELETE removes it, DELETEALL removes all.

:func:`obstacle_update` validates a whole array before anything is applied: one bad marker (a DELETEALL
in a foreign frame included) and the array is refused with a :class:`MessageError` that names it, so a
consumer keeps its previous map. Sizes are bounded by a :class:`~drd_msgs_py.limits.MessageLimits`
(``max_markers``, ``max_line_points``, ``max_mesh_triangles``), counted from the markers' lengths before
any shape is read, and again over the whole map in :meth:`ObstacleUpdate.apply`. Shapes come out as the
plain data of :mod:`drd_msgs_py.shapes`; turning them into collision geometry is the consumer's part.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, TypedDict

import numpy as np

from drd_msgs_py.arrays import FloatArray
from drd_msgs_py.exceptions import MessageError
from drd_msgs_py.factory import MessageFactory, header
from drd_msgs_py.limits import DEFAULT_LIMITS, MessageLimits
from drd_msgs_py.marker_cdr import CdrMarker, MarkerArrayReader, read_marker_array
from drd_msgs_py.shapes import (
    BoxData,
    CylinderData,
    LineStripData,
    MeshData,
    PoseData,
    ShapeData,
    SphereData,
)

__all__ = [
    "CUBE",
    "CYLINDER",
    "LINE_STRIP",
    "SPHERE",
    "TRIANGLE_LIST",
    "MarkerStyle",
    "Obstacle",
    "ObstacleUpdate",
    "markers_from_obstacles",
    "obstacle_update",
    "pose_from_msg",
    "same_obstacle",
]


CUBE, SPHERE, CYLINDER, LINE_STRIP, LINE_LIST, TRIANGLE_LIST = 1, 2, 3, 4, 5, 11
ADD, DELETE, DELETEALL = 0, 2, 3
_TYPE_NAMES = {
    0: "ARROW",
    1: "CUBE",
    2: "SPHERE",
    3: "CYLINDER",
    4: "LINE_STRIP",
    5: "LINE_LIST",
    6: "CUBE_LIST",
    7: "SPHERE_LIST",
    8: "POINTS",
    9: "TEXT_VIEW_FACING",
    10: "MESH_RESOURCE",
    11: "TRIANGLE_LIST",
    12: "ARROW_STRIP",
}
#: Relative tolerance for "equal" marker scales (sphere x = y = z, cylinder x = y).
SCALE_RTOL = 1e-6
#: How far a quaternion's norm may be from 1 before it is refused as malformed.
QUATERNION_TOL = 1e-3
#: LINE_STRIP points closer than this (metres) are one point (nothing between them).
SAME_POINT_M = 1e-9


@dataclass(frozen=True)
class Obstacle:
    """One named obstacle: the shape of one marker and its pose.

    Attributes:
        key: ``"<ns>/<id>"`` of the marker.
        shape: the marker's shape (a LINE_STRIP's points in the marker frame).
        pose: the marker's pose in the message frame.
        kind: the marker type name (``CUBE``, ``LINE_STRIP``, ...).
        points: the marker's point count (LINE_STRIP points, TRIANGLE_LIST vertices; 0 for other types).
        label: where it came from, for error texts (``marker 3 (ns/1)``).
        content: the marker's serialized type, pose, scale and points when it was read from bytes
            (:attr:`CdrMarker.content`), else empty: equal non-empty contents make equal obstacles.
    """

    key: str
    shape: ShapeData
    pose: PoseData
    kind: str
    points: int = 0
    label: str = field(default="", compare=False)
    content: bytes = field(default=b"", compare=False, repr=False)


def same_obstacle(a: Obstacle, b: Obstacle) -> bool:
    """Whether two obstacles are the same marker: key, kind, pose and shape equal (arrays element by element).

    Obstacles read from bytes with equal :attr:`Obstacle.content` are the same without looking further.
    """
    if a is b or (a.content and a.content == b.content and a.key == b.key):
        return True
    if (a.key, a.kind, a.points, a.pose) != (b.key, b.kind, b.points, b.pose) or type(a.shape) is not type(b.shape):
        return False
    if isinstance(a.shape, LineStripData) and isinstance(b.shape, LineStripData):
        return a.shape.diameter == b.shape.diameter and np.array_equal(a.shape.points, b.shape.points)
    if isinstance(a.shape, MeshData) and isinstance(b.shape, MeshData):
        return np.array_equal(a.shape.vertices, b.shape.vertices) and np.array_equal(a.shape.faces, b.shape.faces)
    return a.shape == b.shape


@dataclass(frozen=True)
class ObstacleUpdate:
    """A validated MarkerArray as operations, in message order.

    Attributes:
        operations: ``("clear", "")``, ``("delete", key)`` or ``("add", key)``; each ``add`` key has
            its obstacle in ``obstacles``.
        obstacles: key -> the last obstacle added under that key in this update.
        frame_id: the frame every marker was in.
        limits: the limits the map must stay within after :meth:`apply`.
    """

    operations: tuple[tuple[str, str], ...]
    obstacles: dict[str, Obstacle]
    frame_id: str
    limits: MessageLimits = DEFAULT_LIMITS

    def apply(self, current: dict[str, Obstacle]) -> dict[str, Obstacle]:
        """The obstacle map after this update (a new dict; ``current`` is not changed).

        Raises:
            MessageError: the map would hold more obstacles, LINE_STRIP points or TRIANGLE_LIST triangles than
                :attr:`limits` allow (the text names the limit's parameter); ``current`` stays as it was.
        """
        out = dict(current)
        for op, key in self.operations:
            if op == "clear":
                out.clear()
            elif op == "delete":
                out.pop(key, None)
            else:
                out[key] = self.obstacles[key]
        lines = sum(o.points for o in out.values() if o.kind == "LINE_STRIP")
        triangles = sum(o.points for o in out.values() if o.kind == "TRIANGLE_LIST") // 3
        _check_counts(self.limits, "the obstacle map would have", len(out), lines, triangles)
        return out


def _check_counts(limits: MessageLimits, what: str, markers: int, line_points: int, triangles: int) -> None:
    """MessageError naming the first of ``limits`` that the counts exceed."""
    for name, count, unit in (
        ("max_markers", markers, "obstacles"),
        ("max_line_points", line_points, "LINE_STRIP points"),
        ("max_mesh_triangles", triangles, "TRIANGLE_LIST triangles"),
    ):
        if count > getattr(limits, name):
            raise MessageError(limits.refusal(name, f"{what} {count} {unit}"))


def _finite(values: Sequence[float], what: str) -> tuple[float, ...]:
    try:
        out = tuple(float(v) for v in values)
    except (TypeError, ValueError):
        raise MessageError(f"{what} must be numbers") from None
    if not all(math.isfinite(v) for v in out):
        raise MessageError(f"{what} must be finite, got {out}")
    return out


def pose_from_msg(msg: Any, what: str) -> PoseData:
    """A ``geometry_msgs/Pose`` as :class:`PoseData`; NaN/inf or a non-unit quaternion raise MessageError."""
    p, q = msg.position, msg.orientation
    return _pose_data((p.x, p.y, p.z), (q.x, q.y, q.z, q.w), what)


def _pose_data(xyz: Sequence[float], xyzw: Sequence[float], what: str) -> PoseData:
    """The :class:`PoseData` of a position and a quaternion (see :func:`pose_from_msg`)."""
    position = _finite(xyz, f"{what} position")
    quat = _finite(xyzw, f"{what} orientation")
    norm = math.sqrt(sum(v * v for v in quat))
    if abs(norm - 1.0) > QUATERNION_TOL:
        raise MessageError(f"{what} orientation is not a unit quaternion (norm {norm:.6g})")
    return PoseData((position[0], position[1], position[2]), (quat[0], quat[1], quat[2], quat[3]))


def _points(msg: Any, what: str) -> FloatArray:
    if isinstance(msg, CdrMarker):
        bad = np.flatnonzero(~np.isfinite(msg.points).all(axis=1))
        if bad.size:
            _finite(msg.points[bad[0]].tolist(), f"{what} point {bad[0]}")  # raises, naming the point
        return np.array(msg.points, dtype=np.float64)
    pts = [_finite((p.x, p.y, p.z), f"{what} point {i}") for i, p in enumerate(msg.points)]
    return np.asarray(pts, dtype=np.float64).reshape(-1, 3)


def _positive_scale(values: tuple[float, ...], what: str) -> None:
    if any(v <= 0.0 for v in values):
        raise MessageError(f"{what} must be > 0 (zero-size shapes are refused), got {values}")


def _same(a: float, b: float) -> bool:
    return abs(a - b) <= SCALE_RTOL * max(abs(a), abs(b))


def _line_strip(points: FloatArray, diameter: float, what: str) -> LineStripData:
    if points.shape[0] < 2:
        raise MessageError(f"{what}: a LINE_STRIP needs at least 2 points, got {points.shape[0]}")
    if not np.any(np.linalg.norm(np.diff(points, axis=0), axis=1) > SAME_POINT_M):
        raise MessageError(f"{what}: every LINE_STRIP point is the same (zero-length wire)")
    return LineStripData(points, diameter)


def _triangles(points: FloatArray, what: str) -> MeshData:
    if points.shape[0] < 3 or points.shape[0] % 3:
        raise MessageError(f"{what}: TRIANGLE_LIST needs 3k points (k >= 1), got {points.shape[0]}")
    return MeshData(points, np.arange(points.shape[0], dtype=np.int64).reshape(-1, 3))


def _round_shape(kind: int, scale: tuple[float, ...], what: str) -> ShapeData:
    """The CUBE, SPHERE or CYLINDER of a marker's ``scale`` (metres)."""
    name = _TYPE_NAMES[kind]
    _positive_scale(scale, f"{what} {name} scale")
    if kind == CUBE:
        return BoxData((scale[0], scale[1], scale[2]))
    if kind == SPHERE:
        if not (_same(scale[0], scale[1]) and _same(scale[0], scale[2])):
            raise MessageError(f"{what}: SPHERE scale must be equal on x, y, z (ellipsoids unsupported)")
        return SphereData(scale[0] / 2.0)
    if not _same(scale[0], scale[1]):
        raise MessageError(f"{what}: CYLINDER scale.x and scale.y must be equal (elliptic unsupported)")
    return CylinderData(scale[0] / 2.0, scale[2])


def _obstacle(marker: Any, key: str, what: str) -> Obstacle:
    kind = int(marker.type)
    name = _TYPE_NAMES.get(kind, f"type {kind}")
    if isinstance(marker, CdrMarker):
        pose = _pose_data(marker.values[:3], marker.values[3:7], what)
        scale = _finite(marker.values[7:], f"{what} scale")
    else:
        pose = pose_from_msg(marker.pose, what)
        scale = _finite((marker.scale.x, marker.scale.y, marker.scale.z), f"{what} scale")
    shape: ShapeData
    if kind in (CUBE, SPHERE, CYLINDER):
        shape = _round_shape(kind, scale, what)
    elif kind == LINE_STRIP:
        _positive_scale(scale[:1], f"{what} LINE_STRIP scale.x (diameter)")
        shape = _line_strip(_points(marker, what), scale[0], what)
    elif kind == TRIANGLE_LIST:
        shape = _triangles(_points(marker, what), what)
    else:
        raise MessageError(
            f"{what}: unsupported marker type {name}; use CUBE, SPHERE, CYLINDER, LINE_STRIP or TRIANGLE_LIST"
        )
    points = len(marker.points) if kind in (LINE_STRIP, TRIANGLE_LIST) else 0
    content = marker.content if isinstance(marker, CdrMarker) else b""
    return Obstacle(key, shape, pose, name, points, label=what, content=content)


#: Longest marker namespace accepted (characters); the obstacle map keeps every ``ns/id`` as a key.
MAX_NAMESPACE_CHARS = 256


def _checked_markers(
    msg: Any, frame_id: str, limits: MessageLimits, reader: MarkerArrayReader | None = None
) -> Sequence[Any]:
    """The markers of ``msg`` once every frame and the array's size are checked (see :func:`obstacle_update`)."""
    markers = None
    if isinstance(msg, bytes | bytearray | memoryview):
        markers = read_marker_array(msg, limits) if reader is None else reader.read(msg, limits)
    markers = getattr(msg, "markers", None) if markers is None else markers
    if markers is None:
        raise MessageError("expected a visualization_msgs/MarkerArray (no 'markers' field)")
    if len(markers) > limits.max_markers:
        raise MessageError(limits.refusal("max_markers", f"the MarkerArray has {len(markers)} markers"))
    line_points = triangles = text_bytes = 0
    for i, marker in enumerate(markers):
        ns = str(marker.ns)
        frame = marker.frame_id if isinstance(marker, CdrMarker) else str(marker.header.frame_id)
        text_bytes += len(ns) + len(frame) + len(str(marker.text)) + len(str(marker.mesh_resource))
        if text_bytes > limits.max_message_bytes:
            raise MessageError(
                limits.refusal(
                    "max_message_bytes",
                    f"the MarkerArray's strings (ns, frame_id, text, mesh_resource) "
                    f"reach {text_bytes} characters by marker {i}",
                )
            )
        if len(ns) > MAX_NAMESPACE_CHARS:
            raise MessageError(
                f"marker {i}: its ns has {len(ns)} characters ({ns[:40]!r}...); at most {MAX_NAMESPACE_CHARS} "
                "(the obstacle map keeps every ns/id)"
            )
        if frame != frame_id:
            what = f"marker {i} ({ns[:80]}/{int(marker.id)})"
            raise MessageError(f"{what} is in frame {frame[:80]!r}; the planner works in {frame_id!r}")
        if int(marker.action) == ADD and int(marker.type) == LINE_STRIP:
            line_points += len(marker.points)
        elif int(marker.action) == ADD and int(marker.type) == TRIANGLE_LIST:
            triangles += len(marker.points) // 3
    _check_counts(limits, "the MarkerArray has", 0, line_points, triangles)
    return markers  # type: ignore[no-any-return]


def obstacle_update(
    msg: Any,
    *,
    frame_id: str,
    limits: MessageLimits = DEFAULT_LIMITS,
    held: Mapping[str, Obstacle] | None = None,
    reader: MarkerArrayReader | None = None,
) -> ObstacleUpdate:
    """Validate a MarkerArray (rclpy, rosbags or serialized) and turn it into an :class:`ObstacleUpdate`.

    Every marker's frame is checked first (a DELETEALL in another frame refuses the array like any other
    marker), then the array's size against ``limits`` (markers, LINE_STRIP points, TRIANGLE_LIST triangles,
    counted from the markers' lengths), and only then are shapes built.

    A marker the same as the obstacle ``held`` under its key gives that obstacle object (a caller keeps
    what it built from it): when both were read from bytes and their :attr:`Obstacle.content` is equal,
    without validating the marker again (the same bytes passed the same checks), else once its new obstacle
    is :func:`same_obstacle` as the held one.

    Args:
        msg: ``visualization_msgs/MarkerArray``, or its serialized bytes (:mod:`drd_msgs_py.marker_cdr`).
        frame_id: the planning frame; every marker must be in it (no TF lookups here).
        limits: size limits of one array (and, in :meth:`ObstacleUpdate.apply`, of the map).
        held: the obstacle map the update applies to, key ``ns/id`` (None: build every obstacle).
        reader: reads serialized bytes, reusing the markers of the array it read last where their bytes are
            unchanged (:class:`~drd_msgs_py.marker_cdr.MarkerArrayReader`); None: :func:`read_marker_array`.

    Raises:
        MessageError: a marker in another frame, an array over a size limit (the text names the limit's
            parameter), a marker of an unsupported type or action, with NaN or infinite numbers, a non-unit
            quaternion, a zero or negative size, too few points.
    """
    markers = _checked_markers(msg, frame_id, limits, reader)
    operations: list[tuple[str, str]] = []
    obstacles: dict[str, Obstacle] = {}
    for i, marker in enumerate(markers):
        key = f"{marker.ns}/{int(marker.id)}"
        what = f"marker {i} ({key})"
        action = int(marker.action)
        if action == DELETEALL:
            operations.append(("clear", ""))
        elif action == DELETE:
            operations.append(("delete", key))
        elif action == ADD:
            old = None if held is None else held.get(key)
            if old is not None and old.content and old.content == getattr(marker, "content", None):
                obstacles[key] = old
            else:
                new = _obstacle(marker, key, what)
                obstacles[key] = old if old is not None and same_obstacle(old, new) else new
            operations.append(("add", key))
        else:
            raise MessageError(f"{what}: unsupported marker action {action} (ADD=0, DELETE=2, DELETEALL=3)")
    return ObstacleUpdate(tuple(operations), obstacles, frame_id, limits)


def _pose_msg(msgs: MessageFactory, pose: PoseData) -> Any:
    p, q = pose.position, pose.quaternion_xyzw
    return msgs(
        "geometry_msgs/msg/Pose",
        position=msgs("geometry_msgs/msg/Point", x=float(p[0]), y=float(p[1]), z=float(p[2])),
        orientation=msgs("geometry_msgs/msg/Quaternion", x=float(q[0]), y=float(q[1]), z=float(q[2]), w=float(q[3])),
    )


def _point_msgs(msgs: MessageFactory, points: FloatArray) -> list[Any]:
    return [msgs("geometry_msgs/msg/Point", x=float(x), y=float(y), z=float(z)) for x, y, z in points]


def _shape_fields(msgs: MessageFactory, shape: ShapeData) -> dict[str, Any]:
    """The ``type``, ``scale`` (and ``points``) fields of a marker of ``shape``."""
    points: FloatArray | None = None
    size: tuple[float, ...]
    if isinstance(shape, LineStripData):
        kind, size = LINE_STRIP, (float(shape.diameter), 0.0, 0.0)
        points = np.asarray(shape.points, dtype=np.float64).reshape(-1, 3)
    elif isinstance(shape, BoxData):
        kind, size = CUBE, tuple(float(v) for v in shape.size)
    elif isinstance(shape, SphereData):
        kind, size = SPHERE, (2 * shape.radius,) * 3
    elif isinstance(shape, CylinderData):
        kind, size = CYLINDER, (2 * shape.radius, 2 * shape.radius, shape.length)
    else:
        kind, size = TRIANGLE_LIST, (1.0, 1.0, 1.0)
        points = np.asarray(shape.vertices)[np.asarray(shape.faces).reshape(-1)]
    fields = {"type": kind, "scale": msgs("geometry_msgs/msg/Vector3", x=size[0], y=size[1], z=size[2])}
    if points is not None:
        fields["points"] = _point_msgs(msgs, points)
    return fields


class MarkerStyle(TypedDict, total=False):
    """Optional keywords of :func:`markers_from_obstacles` (its defaults apply), for wrappers that pass them on.

    Attributes:
        stamp: (sec, nanosec) of the headers.
        delete_all_first: start with a DELETEALL marker, so the array replaces the whole map.
        color: RGBA of the markers (for RViz).
    """

    stamp: tuple[int, int]
    delete_all_first: bool
    color: tuple[float, float, float, float]


def markers_from_obstacles(
    obstacles: Sequence[tuple[str, ShapeData, PoseData]],
    *,
    frame_id: str,
    stamp: tuple[int, int] = (0, 0),
    msgs: MessageFactory,
    delete_all_first: bool = True,
    color: tuple[float, float, float, float] = (0.8, 0.3, 0.2, 0.8),
) -> Any:
    """A MarkerArray for ``obstacles``, the inverse of :func:`obstacle_update`.

    Args:
        obstacles: ``(key, shape, pose)``; keys look like ``"ns/id"``. A wire is a :class:`LineStripData`
            (points in the marker frame, usually with the identity pose).
        frame_id: the frame of every marker.
        stamp: (sec, nanosec) of the headers.
        msgs: the message factory (rclpy or rosbags classes).
        delete_all_first: start with a DELETEALL marker, so the array replaces the whole map.
        color: RGBA of the markers (for RViz).

    Raises:
        MessageError: a key that is not ``ns/id``.
    """
    head = header(msgs, frame_id, stamp)
    rgba = msgs("std_msgs/msg/ColorRGBA", r=color[0], g=color[1], b=color[2], a=color[3])
    markers: list[Any] = []
    if delete_all_first:
        markers.append(msgs("visualization_msgs/msg/Marker", header=head, action=DELETEALL))
    for key, shape, pose in obstacles:
        ns, _, ident = key.rpartition("/")
        if not ident.lstrip("-").isdigit():
            raise MessageError(f"obstacle key must look like 'ns/<int id>', got {key!r}")
        fields: dict[str, Any] = {"header": head, "ns": ns, "id": int(ident), "action": ADD, "color": rgba}
        fields |= {"pose": _pose_msg(msgs, pose), **_shape_fields(msgs, shape)}
        markers.append(msgs("visualization_msgs/msg/Marker", **fields))
    return msgs("visualization_msgs/msg/MarkerArray", markers=markers)
