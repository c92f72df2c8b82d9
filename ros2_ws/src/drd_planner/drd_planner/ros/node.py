"""The ``drd_planner`` lifecycle node (rclpy): maps in, lazily checked plans out.

Interface (DESIGN.md section 6; names relative to the node namespace):

- subscriptions (after ``activate``): ``obstacles`` (MarkerArray) and ``terrain`` (PointCloud2), both
  reliable + transient_local depth 1; ``goal_pose`` (PoseStamped) requests, reliable depth 10;
- service ``get_plan`` (``nav_msgs/srv/GetPlan``): the same answer as a ``goal_pose`` request;
- publications: ``plan`` (Path, transient_local), ``edge_checks`` (DiagnosticArray, one status per
  check), ``/diagnostics`` (one summary per request, or the error), ``checked_edges`` (MarkerArray).

Parameters: ``tree_paths`` (tree files; one per goal), ``frame_id`` (planning frame, ``map``), ``seed``,
``max_checks`` (0: no cap), ``goal_tolerance`` (metres).

Consistency: callbacks run one at a time, so a plan runs to its end on the map snapshot it started from;
a map that arrives meanwhile is applied afterwards and is used by the next request. A bad message or a
bad request is reported on ``/diagnostics`` and in the log; it never stops the node, and no plan is
published unless every one of its edges was checked free on the snapshot it was planned on.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Path as PathMsg
from nav_msgs.srv import GetPlan
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.utilities import try_shutdown
from sensor_msgs.msg import PointCloud2
from visualization_msgs.msg import MarkerArray

from drd_msgs_py.exceptions import MessageError
from drd_msgs_py.factory import RclpyMessages
from drd_msgs_py.obstacles import obstacle_update, pose_from_msg
from drd_msgs_py.plans import (
    CheckRecord,
    checked_edges_markers,
    diagnostics_message,
    edge_checks_message,
    path_message,
    summary_status,
)
from drd_msgs_py.terrain import heightfield_from_cloud
from drd_planner.data.tree_file import load_tree
from drd_planner.exceptions import DrdError
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.session import PlanningSession, PlanResult

__all__ = ["PlannerNode", "main"]

LATCHED = QoSProfile(
    depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)
REQUESTS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)


class PlannerNode(LifecycleNode):
    """See the module docstring."""

    def __init__(self, *, node_name: str = "drd_planner", **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        self.declare_parameter("tree_paths", [""])
        self.declare_parameter("frame_id", "map")
        self.declare_parameter("seed", 0)
        self.declare_parameter("max_checks", 0)
        self.declare_parameter("goal_tolerance", 1.0)
        self._msgs = RclpyMessages()
        self._sessions: list[PlanningSession] = []
        self._obstacles: dict[str, Any] = {}
        self._snapshot = MapSnapshot(0)
        self._frame = "map"
        self._subs: list[Any] = []
        self._service: Any = None
        self._plan_pub = self.create_publisher(PathMsg, "plan", LATCHED)
        self._checks_pub = self.create_publisher(DiagnosticArray, "edge_checks", REQUESTS)
        self._diag_pub = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        self._markers_pub = self.create_publisher(MarkerArray, "checked_edges", 10)
        self._errors: list[str] = []

    # ------------------------------------------------------------------------------------------------
    # Introspection (tests, diagnostics)

    @property
    def sessions(self) -> tuple[PlanningSession, ...]:
        """The loaded trees."""
        return tuple(self._sessions)

    @property
    def snapshot(self) -> MapSnapshot:
        """The current maps."""
        return self._snapshot

    @property
    def errors(self) -> tuple[str, ...]:
        """Every error reported so far (also on ``/diagnostics``), oldest first; at most 100 kept."""
        return tuple(self._errors)

    # ------------------------------------------------------------------------------------------------
    # Lifecycle

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Load the trees named in ``tree_paths``; any bad file fails the transition with its reason."""
        paths = [p for p in self.get_parameter("tree_paths").value if p]
        self._frame = str(self.get_parameter("frame_id").value)
        max_checks = int(self.get_parameter("max_checks").value)
        tolerance = float(self.get_parameter("goal_tolerance").value)
        if not paths:
            self._report_error("configure: parameter tree_paths names no tree file")
            return TransitionCallbackReturn.FAILURE
        sessions = []
        for path in paths:
            try:
                bundle = load_tree(path)
                sessions.append(
                    PlanningSession(
                        bundle,
                        name=Path(path).stem,
                        max_checks=max_checks if max_checks > 0 else None,
                        goal_tolerance=tolerance,
                    )
                )
            except DrdError as exc:
                self._report_error(f"configure: {exc}")
                return TransitionCallbackReturn.FAILURE
        margins = {s.margin for s in sessions}
        if len(margins) != 1:
            self._report_error(f"configure: the trees use different collision margins {sorted(margins)}")
            return TransitionCallbackReturn.FAILURE
        self._sessions = sessions
        self._snapshot = MapSnapshot(0, margin=margins.pop())
        self.get_logger().info(f"loaded {len(sessions)} tree(s): {', '.join(s.name for s in sessions)}")
        return TransitionCallbackReturn.SUCCESS

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Subscribe to the maps and requests and offer ``get_plan``."""
        self._subs = [
            self.create_subscription(MarkerArray, "obstacles", self._on_obstacles, LATCHED),
            self.create_subscription(PointCloud2, "terrain", self._on_terrain, LATCHED),
            self.create_subscription(PoseStamped, "goal_pose", self._on_goal, REQUESTS),
        ]
        self._service = self.create_service(GetPlan, "get_plan", self._on_get_plan)
        return TransitionCallbackReturn.SUCCESS

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Stop listening (maps are kept)."""
        self._drop_interfaces()
        return TransitionCallbackReturn.SUCCESS

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Forget the trees and the maps."""
        self._drop_interfaces()
        self._sessions, self._obstacles, self._snapshot = [], {}, MapSnapshot(0)
        return TransitionCallbackReturn.SUCCESS

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Release everything."""
        self._drop_interfaces()
        return TransitionCallbackReturn.SUCCESS

    def _drop_interfaces(self) -> None:
        for sub in self._subs:
            self.destroy_subscription(sub)
        self._subs = []
        if self._service is not None:
            self.destroy_service(self._service)
            self._service = None

    # ------------------------------------------------------------------------------------------------
    # Maps

    def _on_obstacles(self, msg: MarkerArray) -> None:
        try:
            update = obstacle_update(msg, frame_id=self._frame)
        except MessageError as exc:
            self._report_error(f"obstacles refused, map unchanged: {exc}")
            return
        self._obstacles = update.apply(self._obstacles)
        self._snapshot = self._snapshot.with_obstacles({k: o.parts for k, o in self._obstacles.items()})

    def _on_terrain(self, msg: PointCloud2) -> None:
        try:
            terrain = heightfield_from_cloud(msg, frame_id=self._frame)
        except MessageError as exc:
            self._report_error(f"terrain refused, map unchanged: {exc}")
            return
        self._snapshot = self._snapshot.with_terrain(terrain)

    # ------------------------------------------------------------------------------------------------
    # Requests

    def _on_goal(self, msg: PoseStamped) -> None:
        self.plan_for(msg)

    def _on_get_plan(self, request: Any, response: Any) -> Any:
        result = self.plan_for(request.goal)
        response.plan = result if result is not None else PathMsg()
        return response

    def plan_for(self, goal: Any) -> Any | None:
        """Serve one request: the published Path, or None (the reason went to ``/diagnostics``)."""
        try:
            xyz = _goal_xyz(goal, self._frame)
        except MessageError as exc:
            self._report_error(f"request refused: {exc}")
            return None
        session = next((s for s in self._sessions if s.matches_goal(xyz)), None)
        if session is None:
            known = "; ".join(f"{s.name}: {np.round(s.goal_state[:3], 2).tolist()}" for s in self._sessions)
            self._report_error(
                f"request refused: goal {np.round(xyz, 2).tolist()} matches no loaded tree ({known})"
            )
            return None
        snapshot = self._snapshot
        try:
            result = session.plan(snapshot, seed=int(self.get_parameter("seed").value))
        except DrdError as exc:
            self._report_error(f"request refused: {exc}")
            return None
        return self._publish(session, result)

    def _stamp(self) -> tuple[int, int]:
        sec, nsec = self.get_clock().now().seconds_nanoseconds()
        return int(sec), int(nsec)

    def _publish(self, session: PlanningSession, result: PlanResult) -> Any | None:
        stamp = self._stamp()
        records = [
            CheckRecord(c.step, c.edge, c.free, c.stage, c.check_ms, c.endpoints, c.cached)
            for c in result.checks
        ]
        self._checks_pub.publish(edge_checks_message(records, stamp=stamp, msgs=self._msgs))
        self._markers_pub.publish(self._checked_markers(session, result, stamp))
        values = {
            "tree": result.tree,
            "map_version": result.map_version,
            "checks": len(result.checks),
            "free": len(result.checks) - result.num_blocked,
            "blocked": result.num_blocked,
            "tree_checks": sum(c.stage == "tree" for c in result.checks),
            "bisect_checks": sum(c.stage == "bisect" for c in result.checks),
            "check_s": f"{result.seconds.get('checks', 0.0):.4f}",
            "selection_s": f"{result.seconds.get('selection', 0.0):.4f}",
            "total_s": f"{result.seconds.get('total', 0.0):.4f}",
            "result": result.status,
        }
        status = summary_status(ok=result.ok, message=result.message, values=values, msgs=self._msgs)
        self._diag_pub.publish(diagnostics_message([status], stamp=stamp, msgs=self._msgs))
        if not result.ok:
            self.get_logger().warning(f"{result.tree}: {result.message}; nothing published on plan")
            return None
        path = path_message(result.states, frame_id=self._frame, stamp=stamp, msgs=self._msgs)
        self._plan_pub.publish(path)
        self.get_logger().info(f"{result.tree}: {result.message}")
        return path

    def _checked_markers(self, session: PlanningSession, result: PlanResult, stamp: tuple[int, int]) -> Any:
        outcome = {c.edge: int(c.free) for c in result.checks}
        library_edges = session.bundle.problem.library.library_edges
        segments, values = [], []
        for edge in sorted(set(outcome) | {int(e) for e in library_edges}):
            pts = session.edge_states(edge)[:, :3]
            segments.append(np.stack([pts[:-1], pts[1:]], axis=1))
            values.append(np.full(len(pts) - 1, outcome.get(edge, -1)))
        seg = np.concatenate(segments) if segments else np.zeros((0, 2, 3))
        val = np.concatenate(values) if values else np.zeros(0, dtype=np.int64)
        return checked_edges_markers(seg, val, frame_id=self._frame, stamp=stamp, msgs=self._msgs)

    def _report_error(self, text: str) -> None:
        self.get_logger().error(text)
        self._errors = [*self._errors[-99:], text]
        status = summary_status(ok=False, message=text, values={}, msgs=self._msgs)
        self._diag_pub.publish(diagnostics_message([status], stamp=self._stamp(), msgs=self._msgs))


def _goal_xyz(goal: Any, frame: str) -> np.ndarray:
    """(3,) goal position of a PoseStamped in ``frame`` (metres); NaN or a bad quaternion is refused."""
    got = str(goal.header.frame_id)
    if got != frame:
        raise MessageError(f"goal is in frame {got!r}; the planner works in {frame!r}")
    return np.array(pose_from_msg(goal.pose, "goal").position, dtype=np.float64)


def main(args: list[str] | None = None) -> None:
    """``planner_node``: run the lifecycle node (configure and activate it with the lifecycle services)."""
    rclpy.init(args=args)
    node = PlannerNode()
    try:
        rclpy.spin(node)
    except KeyboardInterrupt:
        pass
    finally:
        node.destroy_node()
        try_shutdown()
