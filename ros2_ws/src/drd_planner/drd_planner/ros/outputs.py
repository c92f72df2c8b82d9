"""The node's outputs: its publishers and the messages it sends on them.

``plan``, ``joint_trajectory``, ``edge_checks`` and ``checked_edges`` are lifecycle publishers (silent
until ``activate``); ``/diagnostics`` publishes in every state (errors, map reports, the heartbeat).
Statuses are named after the node (:func:`~drd_planner.ros.status.status_name`). ``plan`` and
``joint_trajectory`` go out serialized, written in bulk from the plan's arrays, and so do the
diagnostics (:mod:`drd_msgs_py.cdr`): as message objects, a Path of 679 poses took 28 ms to build and
convert, more than its plan.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from nav_msgs.msg import Path as PathMsg
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import MarkerArray

from drd_msgs_py.cdr import diagnostic_array_cdr, joint_trajectory_cdr, path_cdr
from drd_msgs_py.factory import RclpyMessages
from drd_msgs_py.plans import (
    EDGE_COLOURS,
    CheckRecord,
    check_statuses,
    checked_edges_markers,
    line_list_marker,
    path_message,
    summary_fields,
)
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.session_plan import SessionPlan
from drd_planner.ros.status import status_name

__all__ = ["CHECK_LOG", "LATCHED", "PlannerOutputs", "SentPlan", "plan_summary_values"]

LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
#: The per-check log.
CHECK_LOG = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
#: Segments per library edge in the grey background of ``checked_edges`` (checked edges are drawn in full).
LIBRARY_EDGE_SEGMENTS = 4
#: Joint speed (rad/s) used to time the published JointTrajectory (its points are evenly spaced).
TRAJECTORY_JOINT_SPEED = 0.5


@dataclass(frozen=True)
class SentPlan:
    """A plan published on ``plan``: what its Path was made of, and the Path as a message object on demand.

    The Path goes out as serialized bytes (:func:`~drd_msgs_py.cdr.path_cdr`); the message object is
    built only when a caller needs one (a ``get_plan`` response), equal to the one sent.

    Attributes:
        states: (K, >= 3) the Path's states: x, y, z (m) and, for the helicopter, heading (rad).
        frame_id: the Path's frame.
        stamp: the Path's stamp (sec, nanosec).
        msgs: the node's message factory.
    """

    states: Any
    frame_id: str
    stamp: tuple[int, int]
    msgs: RclpyMessages

    def path(self) -> Any:
        """The ``nav_msgs/Path`` that was published (built now)."""
        return path_message(self.states, frame_id=self.frame_id, stamp=self.stamp, msgs=self.msgs)


class Session(Protocol):
    """What the outputs read of a planning session (:class:`~drd_planner.planning.session.QuerySession` has it)."""

    @property
    def name(self) -> str: ...
    @property
    def domain(self) -> Any: ...
    @property
    def joint_names(self) -> tuple[str, ...]: ...
    def positions(self, states: Any, snapshot: MapSnapshot | None = None) -> Any: ...
    def edge_states(self, edge: int) -> Any: ...
    def library_edges(self) -> Any: ...


def plan_summary_values(
    result: SessionPlan,
    extra: Mapping[str, Any],
    *,
    wait_s: float,
    plan_messaging_s: float,
    messaging_s: float,
) -> dict[str, Any]:
    """The key/values of a plan's ``<node>: plan`` summary (counts, and times in seconds as text).

    ``prior`` names the prior that planned it (``tree``: the same, a deprecated key kept for one release).
    ``query`` says what served it (``tree:<name>`` a precomputed tree, ``online`` a library and tree
    built for a new query, ``connected`` the same with new motions to off-graph states) and ``stage``
    what proved the path (``probe``, ``lead``, ``tree``, ``bisect``, ``graph``, ...; ``probe_checks``,
    ``lead_checks``, ``tree_checks`` and ``bisect_checks`` count the checks each stage chose); ``result`` is
    the plan's status (``found``, ``no_path``, ``budget_exhausted``, ``refused``) and ``cause`` why it failed
    where the planner can tell (``start_blocked``, ``check_budget``, ...; "" otherwise); ``library_s`` is the
    time spent finding or building the query's library.
    A plan that ran the anytime improvement (``improve_stop`` set) adds ``improvements`` (shorter verified
    paths after the first), ``improve_stop`` (why it stopped), ``improve_checks`` (its checks),
    ``first_cost`` and ``cost`` (path lengths, the first and the published one, in the domain's unit).
    """
    seconds = result.seconds
    values: dict[str, Any] = {
        "prior": result.prior,
        "tree": result.prior,  # deprecated: the prior's name under its old key, for one release
        "query": result.query,
        "stage": result.stage,
        "map_version": result.map_version,
        "checks": len(result.checks),
        "free": len(result.checks) - result.num_blocked,
        "blocked": result.num_blocked,
        "probe_checks": sum(c.stage == "probe" for c in result.checks),
        "lead_checks": sum(c.stage == "lead" for c in result.checks),
        "tree_checks": sum(c.stage == "tree" for c in result.checks),
        "bisect_checks": sum(c.stage == "bisect" for c in result.checks),
        "check_s": f"{seconds.get('checks', 0.0):.6f}",
        "selection_s": f"{seconds.get('selection', 0.0):.6f}",
        "policy_s": f"{seconds.get('policy', 0.0):.6f}",
        "prepare_s": f"{seconds.get('prepare', 0.0):.6f}",
        "library_s": f"{seconds.get('library', 0.0):.6f}",
        "total_s": f"{seconds.get('total', 0.0):.6f}",
        "planning_time": f"{seconds.get('total', 0.0):.6f}",
        "wait_s": f"{wait_s:.6f}",
        "plan_messaging_s": f"{plan_messaging_s:.6f}",
        "messaging_s": f"{messaging_s:.6f}",
        "result": result.status.value,
        "cause": "" if result.cause is None else result.cause.value,
    }
    stop = result.improve_stop
    if stop:
        values["improvements"] = result.improvements
        values["improve_stop"] = stop
        values["improve_checks"] = sum(c.stage == "improve" for c in result.checks)
        values["first_cost"] = f"{result.first_cost:.6f}"
        values["cost"] = f"{result.cost:.6f}"
    return {**values, **extra}


class PlannerOutputs:
    """Publishers of one planner node and the messages on them.

    Args:
        node: the lifecycle node that owns the publishers.
        frame: the planning frame of published paths and markers.
    """

    def __init__(self, node: Any, frame: str = "map") -> None:
        self._node = node
        self.frame = frame
        self.msgs = RclpyMessages()
        self._plan = node.create_lifecycle_publisher(PathMsg, "plan", LATCHED)
        self._trajectory = node.create_lifecycle_publisher(JointTrajectory, "joint_trajectory", LATCHED)
        self._checks = node.create_lifecycle_publisher(DiagnosticArray, "edge_checks", CHECK_LOG)
        self._markers = node.create_lifecycle_publisher(MarkerArray, "checked_edges", 10)
        self._diagnostics = node.create_publisher(DiagnosticArray, "/diagnostics", 10)
        self._library_markers: dict[tuple[str, Any], Any] = {}

    @property
    def active(self) -> bool:
        """Whether the lifecycle publishers are enabled (the node is active)."""
        return bool(self._plan.is_activated)

    def stamp(self) -> tuple[int, int]:
        """Now on the node's clock, (sec, nanosec)."""
        sec, nsec = self._node.get_clock().now().seconds_nanoseconds()
        return int(sec), int(nsec)

    def forget(self) -> None:
        """Drop cached markers (the trees are unloaded)."""
        self._library_markers = {}

    def status(
        self,
        topic: str,
        *,
        ok: bool,
        message: str,
        values: Mapping[str, Any],
        stamp: tuple[int, int] | None = None,
    ) -> None:
        """Publish one ``<node>: <topic>`` status on ``/diagnostics``."""
        name = self._node.get_name()
        status = summary_fields(ok=ok, message=message, values=values, name=status_name(name, topic), hardware_id=name)
        self._diagnostics.publish(diagnostic_array_cdr([status], stamp=stamp or self.stamp()))

    def plan(self, session: Session, result: SessionPlan, snapshot: MapSnapshot, stamp: tuple[int, int]) -> SentPlan:
        """Publish a found plan on ``plan`` (and ``joint_trajectory`` for the arm), serialized from its arrays.

        The arm's JointTrajectory goes first, then its end-effector Path (positions of the plan's
        configurations on ``snapshot``'s robot model).
        """
        if session.domain.publishes_joint_trajectory:
            seconds = float(session.domain.resolution) / TRAJECTORY_JOINT_SPEED
            self._trajectory.publish(
                joint_trajectory_cdr(
                    session.joint_names,
                    result.states,
                    frame_id=self.frame,
                    stamp=stamp,
                    seconds_per_point=seconds,
                )
            )
            states = session.positions(result.states, snapshot)
        else:
            states = result.states
        self._plan.publish(path_cdr(states, frame_id=self.frame, stamp=stamp))
        return SentPlan(states, self.frame, stamp, self.msgs)

    def withdraw(self, session: Session) -> None:
        """Publish an empty ``plan`` (and ``joint_trajectory``): the plan out there is taken back."""
        stamp = self.stamp()
        self._plan.publish(path_cdr(np.zeros((0, 3)), frame_id=self.frame, stamp=stamp))
        if session.domain.publishes_joint_trajectory:
            names = session.joint_names
            self._trajectory.publish(joint_trajectory_cdr(names, np.zeros((0, len(names))), frame_id=self.frame))

    def checks(self, result: SessionPlan, stamp: tuple[int, int]) -> None:
        """Publish the plan's check log on ``edge_checks``."""
        records = [
            CheckRecord(c.step, c.edge, c.free, c.stage, c.check_ms, c.endpoints, c.cached) for c in result.checks
        ]
        self._checks.publish(diagnostic_array_cdr(check_statuses(records), stamp=stamp))

    def markers(self, session: Session, result: SessionPlan, snapshot: MapSnapshot, stamp: tuple[int, int]) -> None:
        """Publish ``checked_edges`` when someone listens (thousands of points)."""
        if self._markers.get_subscription_count() > 0:
            self._markers.publish(self._checked_markers(session, result, snapshot, stamp))

    def _checked_markers(
        self, session: Session, result: SessionPlan, snapshot: MapSnapshot, stamp: tuple[int, int]
    ) -> Any:
        """The checked edges at full resolution over the library edges in grey (built once per tree and arm)."""
        segments, values = [], []
        for check in result.checks:
            pts = session.positions(session.edge_states(check.edge), snapshot)
            segments.append(np.stack([pts[:-1], pts[1:]], axis=1))
            values.append(np.full(len(pts) - 1, int(check.free)))
        seg = np.concatenate(segments) if segments else np.zeros((0, 2, 3))
        val = np.concatenate(values) if values else np.zeros(0, dtype=np.int64)
        library = self._library_marker(session, snapshot)
        library.header.stamp.sec, library.header.stamp.nanosec = stamp
        return checked_edges_markers(seg, val, frame_id=self.frame, stamp=stamp, msgs=self.msgs, background=[library])

    def _library_marker(self, session: Session, snapshot: MapSnapshot) -> Any:
        """Every library edge as a grey LINE_LIST, each drawn with at most :data:`LIBRARY_EDGE_SEGMENTS` segments."""
        key = (session.name, snapshot.robot if session.domain.needs_robot_description else None)
        marker = self._library_markers.get(key)
        if marker is None:
            segments = []
            for edge in session.library_edges():
                pts = session.positions(session.edge_states(int(edge)), snapshot)
                keep = np.unique(np.linspace(0, len(pts) - 1, LIBRARY_EDGE_SEGMENTS + 1).round().astype(int))
                segments.append(np.stack([pts[keep[:-1]], pts[keep[1:]]], axis=1))
            marker = line_list_marker(
                np.concatenate(segments) if segments else np.zeros((0, 2, 3)),
                ns="library",
                rgba=EDGE_COLOURS[-1],
                frame_id=self.frame,
                msgs=self.msgs,
            )
            self._library_markers = {key: marker}  # one tree and arm model at a time is the common case
        return marker
