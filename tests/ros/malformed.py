# mypy: allow-untyped-calls
"""Seeded generator of malformed planner inputs, made by mutating valid rclpy messages (no tests here).

Every generated :class:`Case` carries the message, the topic it goes to, the mutation that made it, whether
the interface (docs/ros-node.md, "Topics, services and actions"; drd_msgs_py validation) *must* refuse it, and
words of which at least one has to appear in the refusal (the reason). A few mutations leave the message valid
on purpose (a repeated LINE_STRIP point, a huge id, some NaN heights, a DELETE with a NaN pose, ...): those
have ``must_fail=False`` and may be accepted.

Valid bases come from the planner's own world models (the helicopter "wires" world of a tree's
domain via :func:`drd_planner.planning.world_messages.helicopter_world_messages`; the arm "table_clutter" world as
CUBE/CYLINDER/SPHERE markers). Messages are copied through rclpy's CDR serialization before being
mutated, so a base is never changed. Same seed, same cases.
"""

from __future__ import annotations

import array
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from geometry_msgs.msg import Point, PoseStamped
from nav_msgs.msg import Odometry
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import JointState, PointCloud2, PointField
from std_msgs.msg import String
from visualization_msgs.msg import Marker, MarkerArray

from drd_msgs_py.factory import RclpyMessages
from drd_planner.planning.world_messages import arm_world_messages, helicopter_world_messages

__all__ = [
    "Case",
    "arm_bases",
    "cloud_cases",
    "description_cases",
    "goal_cases",
    "helicopter_bases",
    "interleave",
    "joint_cases",
    "marker_cases",
    "odom_cases",
]

Rng = np.random.Generator

#: Marker types the planner does not accept (ARROW, LINE_LIST, CUBE_LIST, ..., plus out-of-range ints).
UNKNOWN_TYPES = (0, 5, 6, 7, 8, 9, 10, 12, -1, 13, 99, 2**31 - 1, -(2**31))
#: Marker actions outside ADD (0), DELETE (2), DELETEALL (3).
UNKNOWN_ACTIONS = (1, 4, 5, -1, 42, 2**31 - 1)
#: Frames that are not the planning frame (exact string match, no TF).
WRONG_FRAMES = ("odom", "", "world", "/map", "map ", "MAP", "base_link", "ünïcødé", "x" * 300)
_FINITE = ("finite",)
_QUATERNION = ("unit quaternion",)
_SIZE = ("> 0", "zero-size", "zero size", "positive")


@dataclass(frozen=True)
class Case:
    """One generated input.

    Attributes:
        topic: ``obstacles``, ``terrain``, ``goal_pose``, ``goal_joints`` or ``robot_description``.
        kind: the mutation (``marker/nan_position``, ``cloud/ragged``, ...).
        message: the rclpy message to publish.
        must_fail: the interface requires a refusal; False: the message may be valid after mutation.
        reasons: lower-case words, one of which must appear in the refusal text (empty: any reason).
    """

    topic: str
    kind: str
    message: Any
    must_fail: bool
    reasons: tuple[str, ...]


def _copy(msg: Any) -> Any:
    """A deep copy of an rclpy message (through CDR)."""
    return deserialize_message(serialize_message(msg), type(msg))


def _pick(rng: Rng, options: Sequence[Any]) -> Any:
    return options[int(rng.integers(len(options)))]


def _bad_float(rng: Rng) -> float:
    return float(_pick(rng, (math.nan, math.inf, -math.inf)))


# ------------------------------------------------------------------------------------------------
# Valid bases


def helicopter_bases(domain: Any, *, seed: int, frame_id: str = "map") -> tuple[Any, Any]:
    """(MarkerArray, PointCloud2): the "wires" world of a helicopter domain drawn with ``seed``."""
    world = domain.make_world("wires", seed)
    segments = int(domain.spec().get("wire_segments", 8))
    markers, cloud = helicopter_world_messages(world, wire_segments=segments, frame_id=frame_id, msgs=RclpyMessages())
    return markers, cloud


def arm_bases(domain: Any, *, seed: int, frame_id: str = "panda_link0") -> Any:
    """MarkerArray (DELETEALL first) of the arm domain's "table_clutter" world drawn with ``seed``."""
    world = domain.make_world("table_clutter", seed)
    return arm_world_messages(world, frame_id=frame_id, msgs=RclpyMessages())


# ------------------------------------------------------------------------------------------------
# MarkerArray


_MarkerMutation = Callable[[Rng, Marker], tuple[bool, tuple[str, ...]]]


def _set_vector(rng: Rng, vec: Any, names: str, value: float) -> None:
    setattr(vec, _pick(rng, names), value)


def _nan_position(rng: Rng, m: Marker) -> tuple[bool, tuple[str, ...]]:
    _set_vector(rng, m.pose.position, "xyz", _bad_float(rng))
    return True, _FINITE


def _nan_orientation(rng: Rng, m: Marker) -> tuple[bool, tuple[str, ...]]:
    _set_vector(rng, m.pose.orientation, "xyzw", _bad_float(rng))
    return True, _FINITE


def _nan_scale(rng: Rng, m: Marker) -> tuple[bool, tuple[str, ...]]:
    _set_vector(rng, m.scale, "xyz", _bad_float(rng))
    return True, _FINITE


def _non_unit_quaternion(rng: Rng, m: Marker) -> tuple[bool, tuple[str, ...]]:
    q = m.pose.orientation
    factor = float(_pick(rng, (rng.uniform(1.01, 50.0), rng.uniform(1e-6, 0.99))))
    q.x, q.y, q.z, q.w = q.x * factor, q.y * factor, q.z * factor, q.w * factor
    return True, _QUATERNION


def _zero_quaternion(rng: Rng, m: Marker) -> tuple[bool, tuple[str, ...]]:
    q = m.pose.orientation
    q.x = q.y = q.z = q.w = 0.0
    return True, _QUATERNION


def _solid_or_wire_size(rng: Rng, m: Marker, value: float) -> None:
    """Set the size that matters for the marker's type to ``value``."""
    if m.type == 4:  # LINE_STRIP: the diameter
        m.scale.x = value
    elif m.type == 2:  # SPHERE
        m.scale.x = m.scale.y = m.scale.z = value
    else:
        _set_vector(rng, m.scale, "xyz" if m.type == 1 else "xz", value)
        if m.type == 3:
            m.scale.y = m.scale.x


def _zero_size(rng: Rng, m: Marker) -> tuple[bool, tuple[str, ...]]:
    if m.type == 11:  # a mesh has no size; make it degenerate instead (may be refused or not)
        return _triangle_points(rng, m)
    _solid_or_wire_size(rng, m, 0.0)
    return True, _SIZE


def _negative_size(rng: Rng, m: Marker) -> tuple[bool, tuple[str, ...]]:
    if m.type == 11:
        return _triangle_points(rng, m)
    _solid_or_wire_size(rng, m, -float(rng.uniform(1e-6, 50.0)))
    return True, _SIZE


def _unknown_type(rng: Rng, m: Marker) -> tuple[bool, tuple[str, ...]]:
    m.type = int(_pick(rng, UNKNOWN_TYPES))
    return True, ("unsupported marker type",)


def _unknown_action(rng: Rng, m: Marker) -> tuple[bool, tuple[str, ...]]:
    m.action = int(_pick(rng, UNKNOWN_ACTIONS))
    return True, ("unsupported marker action", "action")


def _wrong_frame(rng: Rng, m: Marker) -> tuple[bool, tuple[str, ...]]:
    m.header.frame_id = str(_pick(rng, WRONG_FRAMES))
    return True, ("frame",)


def _as_line_strip(m: Marker) -> None:
    m.type = 4
    m.scale.x = m.scale.x if m.scale.x > 0 else 0.5
    m.pose.orientation.x = m.pose.orientation.y = m.pose.orientation.z = 0.0
    m.pose.orientation.w = 1.0


def _line_strip_few_points(rng: Rng, m: Marker) -> tuple[bool, tuple[str, ...]]:
    _as_line_strip(m)
    m.points = list(m.points[: int(rng.integers(2))]) or ([Point(x=1.0)] if rng.random() < 0.5 else [])
    return True, ("at least 2 points", "2 points")


def _line_strip_one_point_repeated(rng: Rng, m: Marker) -> tuple[bool, tuple[str, ...]]:
    _as_line_strip(m)
    p = m.points[0] if m.points else Point(x=3.0, y=-2.0, z=50.0)
    m.points = [Point(x=p.x, y=p.y, z=p.z) for _ in range(int(rng.integers(2, 12)))]
    return True, ("zero-length", "same")


def _line_strip_some_repeated(rng: Rng, m: Marker) -> tuple[bool, tuple[str, ...]]:
    """Valid: a wire polyline with a repeated knot (nothing between the two copies)."""
    _as_line_strip(m)
    pts = list(m.points) if len(m.points) >= 2 else [Point(x=0.0), Point(x=10.0, z=5.0)]
    k = int(rng.integers(len(pts)))
    m.points = [*pts[: k + 1], Point(x=pts[k].x, y=pts[k].y, z=pts[k].z), *pts[k + 1 :]]
    return False, ()


def _line_strip_nan_point(rng: Rng, m: Marker) -> tuple[bool, tuple[str, ...]]:
    _as_line_strip(m)
    pts = list(m.points) if len(m.points) >= 2 else [Point(x=0.0), Point(x=10.0, z=5.0)]
    k = int(rng.integers(len(pts)))
    bad = Point(x=pts[k].x, y=pts[k].y, z=pts[k].z)
    _set_vector(rng, bad, "xyz", _bad_float(rng))
    pts[k] = bad
    m.points = pts
    return True, _FINITE


def _triangle_points(rng: Rng, m: Marker) -> tuple[bool, tuple[str, ...]]:
    m.type = 11
    m.scale.x = m.scale.y = m.scale.z = 1.0
    n = int(_pick(rng, (0, 1, 2, 4, 5, 7, 8, 10, 3 * int(rng.integers(1, 30)) + 1)))
    centre = np.array([m.pose.position.x, m.pose.position.y, m.pose.position.z])
    m.pose.position.x = m.pose.position.y = m.pose.position.z = 0.0
    m.pose.orientation.x = m.pose.orientation.y = m.pose.orientation.z = 0.0
    m.pose.orientation.w = 1.0
    pts = np.nan_to_num(centre) + rng.uniform(-5.0, 5.0, size=(n, 3))
    m.points = [Point(x=float(x), y=float(y), z=float(z)) for x, y, z in pts]
    return True, ("3k points", "triangle")


def _unequal_sphere(rng: Rng, m: Marker) -> tuple[bool, tuple[str, ...]]:
    m.type = int(_pick(rng, (2, 3)))
    size = float(rng.uniform(0.5, 20.0))
    m.scale.x, m.scale.y, m.scale.z = size, size * float(rng.uniform(1.1, 3.0)), size
    return True, ("equal",)


def _huge_id(rng: Rng, m: Marker) -> tuple[bool, tuple[str, ...]]:
    """Valid: ids span the whole int32 range."""
    m.id = int(_pick(rng, (2**31 - 1, -(2**31), 2**30 + 7)))
    return False, ()


def _empty_ns(rng: Rng, m: Marker) -> tuple[bool, tuple[str, ...]]:
    """Valid: an empty namespace is allowed (key ``/<id>``)."""
    m.ns = ""
    return False, ()


def _delete_with_nan_pose(rng: Rng, m: Marker) -> tuple[bool, tuple[str, ...]]:
    """Valid: a DELETE names a marker; its pose and scale are not read."""
    m.action = 2
    m.pose.position.x = math.nan
    m.scale.x = -1.0
    return False, ()


_MARKER_MUTATIONS: dict[str, _MarkerMutation] = {
    "nan_position": _nan_position,
    "nan_orientation": _nan_orientation,
    "nan_scale": _nan_scale,
    "non_unit_quaternion": _non_unit_quaternion,
    "zero_quaternion": _zero_quaternion,
    "zero_size": _zero_size,
    "negative_size": _negative_size,
    "unknown_type": _unknown_type,
    "unknown_action": _unknown_action,
    "wrong_frame": _wrong_frame,
    "line_strip_few_points": _line_strip_few_points,
    "line_strip_repeated_point": _line_strip_one_point_repeated,
    "line_strip_nan_point": _line_strip_nan_point,
    "triangle_list_not_3k": _triangle_points,
    "unequal_scale": _unequal_sphere,
    "line_strip_some_repeated": _line_strip_some_repeated,
    "huge_id": _huge_id,
    "empty_ns": _empty_ns,
    "delete_with_nan_pose": _delete_with_nan_pose,
}
#: Mutations that keep the marker valid: drawn with this share of the cases.
_VALID_MARKER_SHARE = 0.04


def marker_cases(rng: Rng, base: Any, *, count: int, max_valid: int = 4) -> list[Case]:
    """``count`` MarkerArrays, each one mutated marker among up to ``max_valid`` valid ones (any order).

    Args:
        rng: the generator (seeded by the caller).
        base: a valid MarkerArray (DELETEALL first, then ADD markers), all in the planning frame.
        count: number of cases.
        max_valid: most valid markers of the base added around the mutated one.
    """
    adds = [m for m in base.markers if m.action == 0]
    if not adds:
        raise ValueError("the base MarkerArray has no ADD marker to mutate")
    valid_kinds = ("line_strip_some_repeated", "huge_id", "empty_ns", "delete_with_nan_pose")
    bad_kinds = [k for k in _MARKER_MUTATIONS if k not in valid_kinds]
    cases = []
    for _ in range(count):
        kind = _pick(rng, valid_kinds) if rng.random() < _VALID_MARKER_SHARE else _pick(rng, bad_kinds)
        bad = _copy(_pick(rng, adds))
        must_fail, reasons = _MARKER_MUTATIONS[kind](rng, bad)
        others = [_copy(_pick(rng, base.markers)) for _ in range(int(rng.integers(max_valid + 1)))]
        others.insert(int(rng.integers(len(others) + 1)), bad)
        cases.append(Case("obstacles", f"marker/{kind}", MarkerArray(markers=others), must_fail, reasons))
    return cases


# ------------------------------------------------------------------------------------------------
# PointCloud2


def _xyz(base: Any) -> np.ndarray:
    """(rows, cols, 3) float32 x, y, z of a float32 xyz cloud with point_step 12."""
    if int(base.point_step) != 12 or [f.name for f in base.fields] != ["x", "y", "z"]:
        raise ValueError("the base cloud must be packed float32 x, y, z")
    raw = np.frombuffer(bytes(base.data), dtype="<f4")
    xyz: np.ndarray = raw.reshape(int(base.height), int(base.width), 3).copy()
    return xyz


def _field(name: str, offset: int, datatype: int = PointField.FLOAT32, count: int = 1) -> PointField:
    return PointField(name=name, offset=offset, datatype=datatype, count=count)


def _cloud(
    base: Any,
    payload: bytes,
    *,
    height: int,
    width: int,
    fields: list[PointField] | None = None,
    point_step: int = 12,
    row_step: int | None = None,
    is_bigendian: bool = False,
) -> PointCloud2:
    msg = PointCloud2()
    msg.header.frame_id = base.header.frame_id
    msg.height, msg.width = height, width
    msg.fields = fields if fields is not None else [_field(n, 4 * k) for k, n in enumerate("xyz")]
    msg.is_bigendian = is_bigendian
    msg.point_step = point_step
    msg.row_step = row_step if row_step is not None else point_step * width
    msg.data = array.array("B", payload)
    msg.is_dense = False
    return msg


def _grid_cloud(base: Any, xyz: np.ndarray, **kwargs: Any) -> PointCloud2:
    rows, cols, _ = xyz.shape
    return _cloud(base, xyz.astype("<f4").tobytes(), height=rows, width=cols, **kwargs)


def _sub_grid(rng: Rng, xyz: np.ndarray) -> np.ndarray:
    """A random window of the grid (>= 2 x 2), so cases vary in size."""
    rows, cols, _ = xyz.shape
    r0, c0 = int(rng.integers(rows - 1)), int(rng.integers(cols - 1))
    r1, c1 = int(rng.integers(r0 + 2, rows + 1)), int(rng.integers(c0 + 2, cols + 1))
    window: np.ndarray = xyz[r0:r1, c0:c1].copy()
    return window


_CloudMutation = Callable[[Rng, Any, np.ndarray], tuple[PointCloud2, bool, tuple[str, ...]]]


def _cloud_empty(rng: Rng, base: Any, xyz: np.ndarray) -> tuple[PointCloud2, bool, tuple[str, ...]]:
    shape = _pick(rng, ((0, 0), (0, 5), (5, 0)))
    return _cloud(base, b"", height=shape[0], width=shape[1]), True, ("organized", "empty")


def _cloud_ragged(rng: Rng, base: Any, xyz: np.ndarray) -> tuple[PointCloud2, bool, tuple[str, ...]]:
    grid = _sub_grid(rng, xyz)
    payload = grid.astype("<f4").tobytes()
    cut = int(rng.integers(len(payload)))
    payload = payload[:cut] if rng.random() < 0.8 else payload + bytes(int(rng.integers(1, 64)))
    rows, cols, _ = grid.shape
    return _cloud(base, payload, height=rows, width=cols), True, ("ragged", "bytes")


def _cloud_point_step(rng: Rng, base: Any, xyz: np.ndarray) -> tuple[PointCloud2, bool, tuple[str, ...]]:
    grid = _sub_grid(rng, xyz)
    step = int(_pick(rng, (0, 4, 8, 11, 13, 16, 24)))
    cols = grid.shape[1]
    msg = _grid_cloud(base, grid, point_step=step, row_step=12 * cols)
    return msg, True, ("point_step", "row_step", "ragged")


def _cloud_missing_field(rng: Rng, base: Any, xyz: np.ndarray) -> tuple[PointCloud2, bool, tuple[str, ...]]:
    grid = _sub_grid(rng, xyz)
    names = ["x", "y", "z"]
    drop = int(rng.integers(3))
    fields = [_field(n, 4 * k) for k, n in enumerate(names) if k != drop]
    if rng.random() < 0.5:
        fields.append(_field(f"{names[drop]}{names[drop]}", 4 * drop))  # a misspelt name
    return _grid_cloud(base, grid, fields=fields), True, ("lacks field", "field")


def _cloud_float64(rng: Rng, base: Any, xyz: np.ndarray) -> tuple[PointCloud2, bool, tuple[str, ...]]:
    grid = _sub_grid(rng, xyz).astype("<f8")
    rows, cols, _ = grid.shape
    fields = [_field(n, 8 * k, datatype=PointField.FLOAT64) for k, n in enumerate("xyz")]
    msg = _cloud(base, grid.tobytes(), height=rows, width=cols, fields=fields, point_step=24)
    return msg, True, ("float32",)


def _cloud_count(rng: Rng, base: Any, xyz: np.ndarray) -> tuple[PointCloud2, bool, tuple[str, ...]]:
    grid = _sub_grid(rng, xyz)
    fields = [_field(n, 4 * k, count=3 if n == "x" else 1) for k, n in enumerate("xyz")]
    return _grid_cloud(base, grid, fields=fields), True, ("float32",)


def _cloud_big_endian(rng: Rng, base: Any, xyz: np.ndarray) -> tuple[PointCloud2, bool, tuple[str, ...]]:
    grid = _sub_grid(rng, xyz)
    rows, cols, _ = grid.shape
    msg = _cloud(base, grid.astype(">f4").tobytes(), height=rows, width=cols, is_bigendian=True)
    return msg, True, ("big-endian", "endian")


def _cloud_non_grid(rng: Rng, base: Any, xyz: np.ndarray) -> tuple[PointCloud2, bool, tuple[str, ...]]:
    grid = _sub_grid(rng, xyz)
    rows, cols, _ = grid.shape
    cell = float(abs(xyz[0, 1, 0] - xyz[0, 0, 0]))
    i, j, axis = int(rng.integers(rows)), int(rng.integers(cols)), int(rng.integers(2))
    # Any single point moved off its cell by more than the tolerance breaks the grid (rows, cols >= 2).
    grid[i, j, axis] += np.float32(cell * float(rng.uniform(0.05, 0.45)) * float(_pick(rng, (-1, 1))))
    if rng.random() < 0.3:  # and the points shuffled: the perturbed one stays off the grid anywhere
        flat = grid.reshape(-1, 3)
        grid = flat[rng.permutation(flat.shape[0])].reshape(rows, cols, 3)
    return _grid_cloud(base, grid), True, ("grid", "spacing")


def _cloud_reversed(rng: Rng, base: Any, xyz: np.ndarray) -> tuple[PointCloud2, bool, tuple[str, ...]]:
    grid = _sub_grid(rng, xyz)[:, ::-1].copy()
    return _grid_cloud(base, grid), True, ("grid", "spacing", "+x")


def _cloud_inf(rng: Rng, base: Any, xyz: np.ndarray) -> tuple[PointCloud2, bool, tuple[str, ...]]:
    grid = _sub_grid(rng, xyz)
    rows, cols, _ = grid.shape
    axis = int(rng.integers(3))
    grid[int(rng.integers(rows)), int(rng.integers(cols)), axis] = np.float32(_pick(rng, (np.inf, -np.inf)))
    return _grid_cloud(base, grid), True, ("finite", "infinite")


def _cloud_nan_xy(rng: Rng, base: Any, xyz: np.ndarray) -> tuple[PointCloud2, bool, tuple[str, ...]]:
    grid = _sub_grid(rng, xyz)
    rows, cols, _ = grid.shape
    grid[int(rng.integers(rows)), int(rng.integers(cols)), int(rng.integers(2))] = np.nan
    return _grid_cloud(base, grid), True, ("finite",)


def _cloud_all_nan(rng: Rng, base: Any, xyz: np.ndarray) -> tuple[PointCloud2, bool, tuple[str, ...]]:
    grid = _sub_grid(rng, xyz)
    grid[..., 2] = np.nan
    return _grid_cloud(base, grid), True, ("no known height", "nan")


def _cloud_unorganized(rng: Rng, base: Any, xyz: np.ndarray) -> tuple[PointCloud2, bool, tuple[str, ...]]:
    grid = _sub_grid(rng, xyz)
    flat = grid.reshape(1, -1, 3)
    if rng.random() < 0.5:
        flat = flat[:, rng.permutation(flat.shape[1])]
    flat = flat.reshape(1, -1, 3) if rng.random() < 0.7 else flat.reshape(-1, 1, 3)
    return _grid_cloud(base, flat), True, ("organized",)


def _cloud_wrong_frame(rng: Rng, base: Any, xyz: np.ndarray) -> tuple[PointCloud2, bool, tuple[str, ...]]:
    msg = _grid_cloud(base, _sub_grid(rng, xyz))
    msg.header.frame_id = str(_pick(rng, WRONG_FRAMES))
    return msg, True, ("frame",)


def _cloud_some_nan(rng: Rng, base: Any, xyz: np.ndarray) -> tuple[PointCloud2, bool, tuple[str, ...]]:
    """Valid: NaN heights are unknown cells (at least one cell keeps its four corners known)."""
    grid = _sub_grid(rng, xyz)
    mask = rng.random(grid.shape[:2]) < float(rng.uniform(0.01, 0.5))
    r, c = int(rng.integers(grid.shape[0] - 1)), int(rng.integers(grid.shape[1] - 1))
    mask[r : r + 2, c : c + 2] = False
    grid[..., 2][mask] = np.nan
    return _grid_cloud(base, grid), False, ()


def _cloud_padded(rng: Rng, base: Any, xyz: np.ndarray) -> tuple[PointCloud2, bool, tuple[str, ...]]:
    """Valid: an extra intensity field and padding at the end of each row."""
    grid = _sub_grid(rng, xyz)
    rows, cols, _ = grid.shape
    points = np.concatenate([grid, rng.random((rows, cols, 1)).astype("<f4")], axis=2)
    pad = int(rng.integers(1, 9)) * 4
    payload = np.zeros((rows, cols * 16 + pad), dtype=np.uint8)
    payload[:, : cols * 16] = np.frombuffer(points.astype("<f4").tobytes(), dtype=np.uint8).reshape(rows, -1)
    fields = [*(_field(n, 4 * k) for k, n in enumerate("xyz")), _field("intensity", 12)]
    msg = _cloud(
        base,
        payload.tobytes(),
        height=rows,
        width=cols,
        fields=fields,
        point_step=16,
        row_step=cols * 16 + pad,
    )
    return msg, False, ()


_CLOUD_MUTATIONS: dict[str, _CloudMutation] = {
    "empty": _cloud_empty,
    "ragged": _cloud_ragged,
    "wrong_point_step": _cloud_point_step,
    "missing_field": _cloud_missing_field,
    "float64_fields": _cloud_float64,
    "field_count": _cloud_count,
    "big_endian": _cloud_big_endian,
    "non_grid_xy": _cloud_non_grid,
    "columns_reversed": _cloud_reversed,
    "inf": _cloud_inf,
    "nan_xy": _cloud_nan_xy,
    "all_nan": _cloud_all_nan,
    "unorganized": _cloud_unorganized,
    "wrong_frame": _cloud_wrong_frame,
    "some_nan": _cloud_some_nan,
    "padded_rows": _cloud_padded,
}
_VALID_CLOUD_KINDS = ("some_nan", "padded_rows")
_VALID_CLOUD_SHARE = 0.04


def cloud_cases(rng: Rng, base: Any, *, count: int) -> list[Case]:
    """``count`` terrain clouds mutated from ``base`` (an organized packed float32 x, y, z cloud)."""
    xyz = _xyz(base)
    bad_kinds = [k for k in _CLOUD_MUTATIONS if k not in _VALID_CLOUD_KINDS]
    cases = []
    for _ in range(count):
        valid = rng.random() < _VALID_CLOUD_SHARE
        kind = _pick(rng, _VALID_CLOUD_KINDS) if valid else _pick(rng, bad_kinds)
        msg, must_fail, reasons = _CLOUD_MUTATIONS[kind](rng, base, xyz)
        cases.append(Case("terrain", f"cloud/{kind}", msg, must_fail, reasons))
    return cases


# ------------------------------------------------------------------------------------------------
# Requests


def goal_cases(rng: Rng, goal: Any, *, count: int, tolerance: float, valid_share: float = 0.01) -> list[Case]:
    """``count`` PoseStamped requests mutated from a valid ``goal`` (a tree's goal position).

    Args:
        rng: the generator.
        goal: a valid request (frame and position of a loaded tree's goal, unit quaternion).
        count: number of cases.
        tolerance: the node's goal tolerance (m); valid goals move within it on one axis, "far" goals lie
            kilometres beyond the graph.
        valid_share: share of still-valid goals (within the tolerance; each one is planned).
    """
    cases = []
    # The zero quaternion is not among them: a goal without orientation is a valid goal with any yaw
    # (tests/planning/test_requests.py).
    kinds = ("nan", "wrong_frame", "far_away", "non_unit_quaternion")
    for _ in range(count):
        msg = _copy(goal)
        if rng.random() < valid_share:
            axis = _pick(rng, "xyz")
            setattr(msg.pose.position, axis, getattr(msg.pose.position, axis) + rng.uniform(-0.5, 0.5) * tolerance)
            cases.append(Case("goal_pose", "goal/within_tolerance", msg, False, ()))
            continue
        kind = _pick(rng, kinds)
        reasons: tuple[str, ...]
        if kind == "nan":
            _set_vector(rng, _pick(rng, (msg.pose.position, msg.pose.orientation)), "xyz", _bad_float(rng))
            reasons = _FINITE
        elif kind == "wrong_frame":
            msg.header.frame_id = str(_pick(rng, WRONG_FRAMES))
            reasons = ("frame",)
        elif kind == "far_away":
            # Beyond the graph's reach (a prior plans any goal a motion can join: 100 m for the
            # helicopter lattice); goals just off a vertex are valid requests now.
            axis = _pick(rng, "xyz")
            offset = float(rng.uniform(2e3, 1e7))
            setattr(msg.pose.position, axis, getattr(msg.pose.position, axis) + offset * _pick(rng, (-1, 1)))
            reasons = ("reach", "goal")
        else:
            q = msg.pose.orientation
            q.w = float(rng.uniform(1.01, 100.0)) * _pick(rng, (-1.0, 1.0))
            reasons = _QUATERNION
        cases.append(Case("goal_pose", f"goal/{kind}", msg, True, reasons))
    return cases


def joint_cases(rng: Rng, goal: Any, *, count: int) -> list[Case]:
    """``count`` JointState requests mutated from a valid ``goal`` (names panda_joint1..7, radians)."""
    names, positions = list(goal.name), list(goal.position)
    cases = []
    kinds = ("wrong_names", "wrong_count", "nan", "empty", "duplicate_names")
    for _ in range(count):
        msg = _copy(goal)
        kind = _pick(rng, kinds)
        reasons: tuple[str, ...]
        if kind == "wrong_names":
            k = int(rng.integers(len(names)))
            msg.name = [
                *names[:k],
                _pick(rng, ("panda_joint8", "", "joint1", "panda_finger_joint1")),
                *names[k + 1 :],
            ]
            reasons = ("joint", "name")
        elif kind == "wrong_count":
            n = int(_pick(rng, (0, 1, 3, 6, 8, 9, 20)))
            if rng.random() < 0.5:  # the right names, too few or too many positions
                msg.position = [float(v) for v in (positions * 3)[:n]]
            else:  # n names and positions: too few misses joints; extra unknown joints may be ignored
                msg.name = [f"panda_joint{i + 1}" for i in range(n)]
                msg.position = [float(v) for v in (positions * 3)[:n]]
                if n > len(names):
                    cases.append(Case("goal_joints", "joints/extra_joints", msg, False, ()))
                    continue
            reasons = ("joint", "position", "name", "count", "7")
        elif kind == "nan":
            k = int(rng.integers(len(positions)))
            msg.position = [*positions[:k], _bad_float(rng), *positions[k + 1 :]]
            reasons = ("finite", "nan")
        elif kind == "empty":
            msg.name, msg.position = [], []
            reasons = ("joint", "position", "name", "empty")
        else:
            msg.name = [names[0], *names[:-1]]
            reasons = ("joint", "name", "duplicate")
        cases.append(Case("goal_joints", f"joints/{kind}", msg, True, reasons))
    return cases


def description_cases(rng: Rng, urdf: str, *, count: int) -> list[Case]:
    """``count`` robot_description strings mutated from a valid URDF text (all invalid)."""
    text = urdf.rstrip()
    root_open = text.find("<robot")
    cases = []
    for _ in range(count):
        kind = _pick(rng, ("empty", "not_xml", "no_joints", "truncated", "other_robot"))
        if kind == "empty":
            data = str(_pick(rng, ("", " ", "\n\t")))
        elif kind == "not_xml":
            data = str(_pick(rng, ("hello", "{}", "robot: panda", "<<>>", "\x00\x01", "<robot", "42")))
        elif kind == "no_joints":
            data = '<?xml version="1.0"?><robot name="empty"><link name="panda_link0"/></robot>'
        elif kind == "truncated":
            data = text[: int(rng.integers(root_open + 1, len(text) - 1))]
        else:  # a well-formed robot with another chain
            data = (
                '<robot name="other"><link name="a"/><link name="b"/>'
                '<joint name="j1" type="revolute"><parent link="a"/><child link="b"/>'
                '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>'
            )
        reasons = ("urdf", "xml", "joint", "robot", "empty", "parse", "description")
        cases.append(Case("robot_description", f"description/{kind}", String(data=data), True, reasons))
    return cases


def interleave(rng: Rng, *groups: list[Case]) -> list[Case]:
    """All cases of ``groups`` in one seeded random order."""
    cases = [c for group in groups for c in group]
    return [cases[i] for i in rng.permutation(len(cases))]


def odom_cases(rng: Rng, odom: Any, *, count: int) -> list[Case]:
    """``count`` malformed Odometry messages (the robot's state) mutated from a valid ``odom``; all must fail."""
    cases = []
    for _ in range(count):
        msg = _copy(odom)
        pose = msg.pose.pose
        kind = _pick(rng, ("nan", "wrong_frame", "zero_quaternion", "non_unit_quaternion"))
        reasons: tuple[str, ...]
        if kind == "nan":
            _set_vector(rng, _pick(rng, (pose.position, pose.orientation)), "xyz", _bad_float(rng))
            reasons = _FINITE
        elif kind == "wrong_frame":
            msg.header.frame_id = str(_pick(rng, WRONG_FRAMES))
            reasons = ("frame",)
        elif kind == "zero_quaternion":
            pose.orientation.x = pose.orientation.y = pose.orientation.z = pose.orientation.w = 0.0
            reasons = _QUATERNION
        else:
            pose.orientation.w = float(rng.uniform(1.01, 100.0)) * _pick(rng, (-1.0, 1.0))
            reasons = _QUATERNION
        cases.append(Case("odom", f"odom/{kind}", msg, True, reasons))
    return cases


def valid_odometry(state: npt.ArrayLike, *, frame_id: str) -> Odometry:
    """An Odometry at a (4,) helicopter state (x, y, z m, heading rad) in ``frame_id``."""
    x, y, z, yaw = (float(v) for v in np.asarray(state, dtype=np.float64).ravel()[:4])
    odom = Odometry()
    odom.header.frame_id = frame_id
    odom.pose.pose.position.x, odom.pose.pose.position.y, odom.pose.pose.position.z = x, y, z
    odom.pose.pose.orientation.z, odom.pose.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    return odom


def valid_goal(xyz: npt.ArrayLike, *, frame_id: str) -> PoseStamped:
    """A PoseStamped at ``xyz`` (metres) in ``frame_id`` with the identity orientation."""
    goal = PoseStamped()
    goal.header.frame_id = frame_id
    x, y, z = (float(v) for v in np.asarray(xyz, dtype=np.float64).ravel()[:3])
    goal.pose.position.x, goal.pose.position.y, goal.pose.position.z = x, y, z
    goal.pose.orientation.w = 1.0
    return goal


def valid_joints(names: Sequence[str], positions: npt.ArrayLike) -> JointState:
    """A JointState with ``names`` and ``positions`` (radians)."""
    values = np.asarray(positions, dtype=np.float64).ravel()
    return JointState(name=list(names), position=[float(v) for v in values])
