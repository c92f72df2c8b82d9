"""Builders for what the planner publishes: the plan, the check log, the summary and RViz markers.

All take a :class:`~drd_msgs_py.factory.MessageFactory`, so the same code makes rclpy messages for
the node and rosbags messages for bags and tests. Shapes: ``states`` (K, >= 3) metres (x, y, z and,
for the helicopter, heading in radians as column 3); joint positions (K, J) radians.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_msgs_py.factory import MessageFactory, header

__all__ = [
    "CheckRecord",
    "StatusFields",
    "check_statuses",
    "checked_edges_markers",
    "edge_checks_message",
    "joint_trajectory_message",
    "path_message",
    "path_poses",
    "status_message",
    "summary_fields",
    "summary_status",
    "trajectory_positions",
    "trajectory_times",
]

OK, WARN, ERROR = 0, 1, 2
_LINE_LIST, _DELETEALL, _ADD = 5, 3, 0


@dataclass(frozen=True)
class CheckRecord:
    """One edge check as the node reports it.

    Attributes:
        step: 1-based position in the plan's check order.
        edge: edge id.
        free: outcome.
        stage: ``tree`` or ``bisect`` (which part of the method chose the edge).
        check_ms: wall time of the collision check, ms (0 when answered from the cache).
        endpoints: the edge's (u, v) vertex ids.
        cached: whether the outcome came from the per-map-snapshot cache.
    """

    step: int
    edge: int
    free: bool
    stage: str
    check_ms: float
    endpoints: tuple[int, int]
    cached: bool = False


def path_poses(states: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """(K, 7) poses x, y, z (m), qx, qy, qz, qw of (K, >= 3) states; column 3 (if present) is the heading in radians.

    The one reading of plan states as poses, for :func:`path_message` and
    :func:`~drd_msgs_py.cdr.path_cdr`: the orientation is the heading about z (no heading: identity).

    Raises:
        ValueError: ``states`` is not (K, >= 3).
    """
    pts = np.asarray(states, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] < 3:
        raise ValueError(f"path states must be (K, >= 3), got {pts.shape}")
    yaw = pts[:, 3] if pts.shape[1] > 3 else np.zeros(len(pts))
    poses = np.zeros((len(pts), 7))
    poses[:, :3] = pts[:, :3]
    poses[:, 5] = np.sin(yaw / 2.0)
    poses[:, 6] = np.cos(yaw / 2.0)
    return poses


def path_message(states: npt.ArrayLike, *, frame_id: str, stamp: tuple[int, int] = (0, 0), msgs: MessageFactory) -> Any:
    """``nav_msgs/Path`` through (K, >= 3) states; column 3 (if present) is the heading in radians.

    Every pose shares the Path's header (frame and stamp). The node publishes the same message as
    CDR bytes (:func:`~drd_msgs_py.cdr.path_cdr`, decoded equal); this builds the message object
    (a ``get_plan`` response, bags, tests).
    """
    head = header(msgs, frame_id, stamp)
    poses = []
    for x, y, z, _, _, qz, qw in path_poses(states).tolist():  # fill each new message's own fields
        stamped = msgs("geometry_msgs/msg/PoseStamped", header=head)
        position, orientation = stamped.pose.position, stamped.pose.orientation
        position.x, position.y, position.z = x, y, z
        orientation.x, orientation.y, orientation.z, orientation.w = 0.0, 0.0, qz, qw
        poses.append(stamped)
    return msgs("nav_msgs/msg/Path", header=head, poses=poses)


def trajectory_positions(joint_names: Sequence[str], positions: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """(K, J) joint positions (radians) as float64, J = ``len(joint_names)``.

    Raises:
        ValueError: ``positions`` is not (K, J).
    """
    q = np.asarray(positions, dtype=np.float64)
    if q.ndim != 2 or q.shape[1] != len(joint_names):
        raise ValueError(f"positions must be (K, {len(joint_names)}), got {q.shape}")
    return q


def trajectory_times(count: int, seconds_per_point: float) -> npt.NDArray[np.int64]:
    """(K, 2) ``time_from_start`` (sec, nanosec) of K evenly timed points: point k at k * ``seconds_per_point`` s.

    nanosec is the fraction rounded half to even (as Python's ``round``), so the points of
    :func:`joint_trajectory_message` and :func:`~drd_msgs_py.cdr.joint_trajectory_cdr` agree.
    """
    t = np.arange(count, dtype=np.float64) * float(seconds_per_point)
    whole = np.trunc(t)
    times = np.empty((count, 2), dtype=np.int64)
    times[:, 0] = whole
    times[:, 1] = np.rint((t - whole) * 1e9)
    return times


def joint_trajectory_message(
    joint_names: Sequence[str],
    positions: npt.ArrayLike,
    *,
    frame_id: str,
    stamp: tuple[int, int] = (0, 0),
    seconds_per_point: float = 1.0,
    msgs: MessageFactory,
) -> Any:
    """``trajectory_msgs/JointTrajectory`` through (K, J) joint positions (radians), evenly timed.

    The node publishes the same message as CDR bytes (:func:`~drd_msgs_py.cdr.joint_trajectory_cdr`).
    """
    q = trajectory_positions(joint_names, positions)
    points = [
        msgs(
            "trajectory_msgs/msg/JointTrajectoryPoint",
            positions=row.copy(),  # its own array, not a view of the caller's
            time_from_start=msgs("builtin_interfaces/msg/Duration", sec=sec, nanosec=nanosec),
        )
        for row, (sec, nanosec) in zip(q, trajectory_times(len(q), seconds_per_point).tolist(), strict=True)
    ]
    return msgs(
        "trajectory_msgs/msg/JointTrajectory",
        header=header(msgs, frame_id, stamp),
        joint_names=list(joint_names),
        points=points,
    )


@dataclass(frozen=True)
class StatusFields:
    """One ``diagnostic_msgs/DiagnosticStatus`` as plain data.

    What :func:`status_message` builds as a message and :func:`~drd_msgs_py.cdr.diagnostic_array_cdr`
    writes as bytes, so both send the same status.

    Attributes:
        level: OK (0), WARN (1) or ERROR (2).
        name: the status's name (``edge/<id>``, ``<node>: plan``, ...).
        message: its one-line text.
        hardware_id: what it is about (the node).
        values: its key/value pairs as text, in order.
    """

    level: int
    name: str
    message: str
    hardware_id: str
    values: tuple[tuple[str, str], ...] = ()

    @classmethod
    def of(cls, level: int, name: str, message: str, hardware_id: str, values: Mapping[str, Any]) -> StatusFields:
        """The status with ``values`` as text (``str`` of each key and value)."""
        return cls(level, name, message, hardware_id, tuple((str(k), str(v)) for k, v in values.items()))


def status_message(fields: StatusFields, *, msgs: MessageFactory) -> Any:
    """The ``diagnostic_msgs/DiagnosticStatus`` of ``fields``."""
    return msgs(
        "diagnostic_msgs/msg/DiagnosticStatus",
        level=fields.level,
        name=fields.name,
        message=fields.message,
        hardware_id=fields.hardware_id,
        values=[msgs("diagnostic_msgs/msg/KeyValue", key=k, value=v) for k, v in fields.values],
    )


def check_statuses(checks: Sequence[CheckRecord], *, hardware_id: str = "drd_planner") -> list[StatusFields]:
    """One status per check in order: OK ``free`` or ERROR ``in collision``; step, stage, check_ms, cached, u, v."""
    return [
        StatusFields.of(
            OK if c.free else ERROR,
            f"edge/{c.edge}",
            "free" if c.free else "in collision",
            hardware_id,
            {
                "step": c.step,
                "stage": c.stage,
                "check_ms": f"{c.check_ms:.3f}",
                "cached": str(c.cached).lower(),
                "u": c.endpoints[0],
                "v": c.endpoints[1],
            },
        )
        for c in checks
    ]


def edge_checks_message(
    checks: Sequence[CheckRecord],
    *,
    stamp: tuple[int, int] = (0, 0),
    hardware_id: str = "drd_planner",
    msgs: MessageFactory,
) -> Any:
    """``diagnostic_msgs/DiagnosticArray``: one status per check, in order (:func:`check_statuses`)."""
    status = [status_message(f, msgs=msgs) for f in check_statuses(checks, hardware_id=hardware_id)]
    return msgs("diagnostic_msgs/msg/DiagnosticArray", header=header(msgs, "", stamp), status=status)


def summary_fields(
    *,
    ok: bool,
    message: str,
    values: Mapping[str, Any],
    name: str = "drd_planner: plan",
    hardware_id: str = "drd_planner",
    level: int | None = None,
) -> StatusFields:
    """The status summarising a request (OK, or ERROR with the reason in ``message``; ``level`` overrides)."""
    return StatusFields.of((OK if ok else ERROR) if level is None else level, name, message, hardware_id, values)


def summary_status(
    *,
    ok: bool,
    message: str,
    values: Mapping[str, Any],
    name: str = "drd_planner: plan",
    hardware_id: str = "drd_planner",
    level: int | None = None,
    msgs: MessageFactory,
) -> Any:
    """One ``DiagnosticStatus`` summarising a request (:func:`summary_fields`)."""
    fields = summary_fields(ok=ok, message=message, values=values, name=name, hardware_id=hardware_id, level=level)
    return status_message(fields, msgs=msgs)


def diagnostics_message(statuses: Sequence[Any], *, stamp: tuple[int, int] = (0, 0), msgs: MessageFactory) -> Any:
    """``diagnostic_msgs/DiagnosticArray`` of ``statuses``."""
    return msgs("diagnostic_msgs/msg/DiagnosticArray", header=header(msgs, "", stamp), status=list(statuses))


#: RGBA of the checked-edge markers: free, blocked, not checked.
EDGE_COLOURS = {1: (0.1, 0.8, 0.2, 1.0), 0: (0.9, 0.1, 0.1, 1.0), -1: (0.6, 0.6, 0.6, 0.5)}
_EDGE_NAMES = {1: "free", 0: "blocked", -1: "unchecked"}


def line_list_marker(
    segments: npt.ArrayLike,
    *,
    ns: str,
    rgba: tuple[float, float, float, float],
    frame_id: str,
    stamp: tuple[int, int] = (0, 0),
    width: float = 2.0,
    msgs: MessageFactory,
) -> Any:
    """One RViz LINE_LIST ``Marker`` (id 0 in ``ns``) through (S, 2, 3) segments in metres."""
    seg = np.asarray(segments, dtype=np.float64).reshape(-1, 2, 3)
    point = msgs("geometry_msgs/msg/Point")
    point_class = type(point)
    try:  # the message class itself is much faster than the factory for thousands of points
        points = [point_class(x=x, y=y, z=z) for x, y, z in seg.reshape(-1, 3).tolist()]
    except TypeError:
        points = [msgs("geometry_msgs/msg/Point", x=x, y=y, z=z) for x, y, z in seg.reshape(-1, 3).tolist()]
    return msgs(
        "visualization_msgs/msg/Marker",
        header=header(msgs, frame_id, stamp),
        ns=ns,
        id=0,
        type=_LINE_LIST,
        action=_ADD,
        pose=msgs("geometry_msgs/msg/Pose", orientation=msgs("geometry_msgs/msg/Quaternion", w=1.0)),
        scale=msgs("geometry_msgs/msg/Vector3", x=width),
        color=msgs("std_msgs/msg/ColorRGBA", r=rgba[0], g=rgba[1], b=rgba[2], a=rgba[3]),
        points=points,
    )


def checked_edges_markers(
    segments: npt.ArrayLike,
    outcome: npt.ArrayLike,
    *,
    frame_id: str,
    stamp: tuple[int, int] = (0, 0),
    width: float = 2.0,
    msgs: MessageFactory,
    background: Sequence[Any] = (),
) -> Any:
    """RViz LINE_LISTs after a DELETEALL: green free, red blocked, grey unchecked library edges.

    Args:
        segments: (S, 2, 3) polyline segments (metres); an edge's trajectory gives several.
        outcome: (S,) per segment 1 = free, 0 = blocked, -1 = not checked.
        frame_id: frame of the markers.
        stamp: (sec, nanosec) of the headers.
        width: line width, metres.
        msgs: the message factory.
        background: ready markers drawn first (e.g. every library edge in grey, built once per tree).
    """
    seg = np.asarray(segments, dtype=np.float64).reshape(-1, 2, 3)
    out = np.asarray(outcome, dtype=np.int64).reshape(-1)
    if out.shape[0] != seg.shape[0]:
        raise ValueError("one outcome per segment")
    markers = [msgs("visualization_msgs/msg/Marker", header=header(msgs, frame_id, stamp), action=_DELETEALL)]
    markers.extend(background)
    for value in (-1, 0, 1):
        rows = seg[out == value]
        if rows.size:
            markers.append(
                line_list_marker(
                    rows,
                    ns=_EDGE_NAMES[value],
                    rgba=EDGE_COLOURS[value],
                    frame_id=frame_id,
                    stamp=stamp,
                    width=width,
                    msgs=msgs,
                )
            )
    return msgs("visualization_msgs/msg/MarkerArray", markers=markers)
