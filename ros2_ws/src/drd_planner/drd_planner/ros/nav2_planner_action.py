"""Nav2's ``compute_path_to_pose`` action (``nav2_msgs/action/ComputePathToPose``, Jazzy) on the planner.

Goal: ``goal`` (PoseStamped), ``start`` (PoseStamped, used when ``use_start``; otherwise the robot's state
from odometry, as Nav2 takes the robot's pose), ``planner_id`` ("" or the name of a loaded prior, e.g.
``heli_wires``). Result: ``path`` (nav_msgs/Path: the plan's poses, every edge checked free on the maps it
was planned on; the same plan is published on ``plan`` as a ``get_plan`` would), ``planning_time``,
``error_code`` and ``error_msg``: one Nav2 code per failure
(:mod:`drd_planner.planning.nav2_codes`). A goal succeeds with a path, or is aborted with its code.

Frames: a pose in the planning frame (``frame_id``), or with an empty frame (taken as the planning frame);
another frame is ``TF_ERROR`` (the node does no transforms).

Cancellation: a cancel request is accepted at once and stops the plan before its next collision check
(:mod:`drd_planner.planning.cancel`); the goal then ends CANCELED with an empty result, as in Nav2's planner
server, and nothing is published. Goals are planned one at a time with the node's other requests; each
accepted goal runs in its own executor thread (:mod:`drd_planner.ros.nav2_host`).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from builtin_interfaces.msg import Duration
from rclpy.action.server import ActionServer, CancelResponse

from drd_msgs_py.exceptions import MessageError
from drd_planner.exceptions import DrdError
from drd_planner.planning.cancel import CancelToken, PlanCancelled
from drd_planner.planning.nav2_codes import Nav2Error, nav2_error
from drd_planner.planning.path_validity import ServedPaths
from drd_planner.planning.requests import Goal, goal_from_pose
from drd_planner.planning.service import PlannerService

__all__ = ["ACTION_NAME", "PlannerActionServer", "duration_of", "request_poses"]

#: The action's name, relative to the node's namespace (Nav2's planner server's).
ACTION_NAME = "compute_path_to_pose"


def duration_of(seconds: float) -> Duration:
    """A ``builtin_interfaces/Duration`` of ``seconds`` (>= 0)."""
    whole = int(max(seconds, 0.0))
    return Duration(sec=whole, nanosec=int((max(seconds, 0.0) - whole) * 1e9))


def request_poses(request: Any, frame: str) -> tuple[Goal, Goal | None] | Nav2Error:
    """A ComputePathToPose goal's goal and start (None: the robot's state), or the error that refuses them.

    An empty frame is taken as ``frame`` (the planning frame; the message is changed); another is ``TF_ERROR``.
    """
    poses = [("goal", request.goal)] + ([("start", request.start)] if request.use_start else [])
    for what, pose in poses:
        got = str(pose.header.frame_id)
        if got == "":
            pose.header.frame_id = frame  # Nav2 clients may leave it empty: the planning frame
        elif got != frame:
            text = f"{what} is in frame {got[:80]!r}; the planner works in {frame!r} and does no transforms"
            return Nav2Error("TF_ERROR", text)
    try:
        goal = goal_from_pose(request.goal, frame)
        start = goal_from_pose(request.start, frame, "start") if request.use_start else None
    except (MessageError, DrdError) as exc:
        return Nav2Error("UNKNOWN", f"{ACTION_NAME} refused: {exc}")
    return goal, start


class PlannerActionServer:
    """Serves ``compute_path_to_pose`` on ``node`` (see the module docstring).

    Args:
        node: the companion node (:class:`~drd_planner.ros.nav2_host.Nav2Host`).
        action_type: ``nav2_msgs.action.ComputePathToPose``.
        service: the planner service the node plans with.
        served: where each returned path is remembered for ``is_path_valid``.
        group: the callback group (reentrant: a cancel is heard while a goal plans).
        report: reports an internal error (the node's log and ``/diagnostics``).
    """

    def __init__(
        self,
        node: Any,
        action_type: Any,
        service: PlannerService,
        served: ServedPaths,
        *,
        group: Any,
        report: Callable[[str], None],
    ) -> None:
        self._type = action_type
        self._service = service
        self._served = served
        self._report = report
        self._tokens: dict[bytes, CancelToken] = {}
        self._lock = threading.Lock()
        self._server = ActionServer(
            node,
            action_type,
            ACTION_NAME,
            execute_callback=self._execute,
            cancel_callback=self._on_cancel,
            callback_group=group,
        )
        self.name = f"{node.get_namespace().rstrip('/')}/{ACTION_NAME}"

    def _token(self, goal_handle: Any) -> CancelToken:
        with self._lock:
            return self._tokens.setdefault(bytes(goal_handle.goal_id.uuid), CancelToken())

    def _on_cancel(self, goal_handle: Any) -> CancelResponse:
        """Accept every cancel request; the goal's plan stops before its next check."""
        self._token(goal_handle).cancel()
        return CancelResponse.ACCEPT

    def cancel_all(self) -> None:
        """Cancel every running goal's plan (the node deactivates)."""
        with self._lock:
            for token in self._tokens.values():
                token.cancel()

    def _execute(self, goal_handle: Any) -> Any:
        """Plan one goal: succeed with the path, abort with a Nav2 code, or end CANCELED."""
        started = time.perf_counter()
        token = self._token(goal_handle)
        try:
            return self._serve(goal_handle, token, started)
        except PlanCancelled as stop:
            goal_handle.canceled()
            return self._type.Result(error_msg=f"canceled: the plan stopped {stop}")
        except Exception as exc:  # a bug must not end the node: the goal is aborted, the error reported
            self._report(f"{ACTION_NAME}: internal error: {type(exc).__name__}: {exc}")
            return self._end(goal_handle, Nav2Error("UNKNOWN", f"internal error: {exc}"), started)
        finally:
            with self._lock:
                self._tokens.pop(bytes(goal_handle.goal_id.uuid), None)

    def _serve(self, goal_handle: Any, token: CancelToken, started: float) -> Any:
        request = goal_handle.request
        names = [s.name for s in self._service.sessions]
        if request.planner_id and request.planner_id not in names:
            text = f"planner_id {request.planner_id!r} names no loaded prior (planner ids: {', '.join(names)})"
            return self._end(goal_handle, Nav2Error("INVALID_PLANNER", text), started)
        parsed = request_poses(request, self._service.frame_id)
        if isinstance(parsed, Nav2Error):
            return self._end(goal_handle, parsed, started)
        outcome = self._service.serve_request(*parsed, ACTION_NAME, cancel=token)
        token.check(len(outcome.result.checks) if outcome.result is not None else 0)  # cancelled at the end
        error = nav2_error(outcome)
        if error.name != "NONE" or outcome.sent is None:
            return self._end(
                goal_handle, error if error.name != "NONE" else Nav2Error("UNKNOWN", "not published"), started
            )
        assert outcome.result is not None and outcome.session is not None and outcome.snapshot is not None
        self._served.remember(outcome.session, outcome.result.path_edges, outcome.sent.states, outcome.snapshot)
        goal_handle.succeed()
        return self._type.Result(path=outcome.sent.path(), planning_time=duration_of(time.perf_counter() - started))

    def _end(self, goal_handle: Any, error: Nav2Error, started: float) -> Any:
        """Abort the goal with ``error`` (its code and text)."""
        goal_handle.abort()
        return self._type.Result(
            error_code=error.code,
            error_msg=error.text,
            planning_time=duration_of(time.perf_counter() - started),
        )
