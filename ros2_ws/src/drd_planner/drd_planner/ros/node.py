"""The ``drd_planner`` lifecycle node (rclpy): maps and the robot's state in, lazily checked plans out.

Interface (names relative to the node namespace):

- subscriptions (after ``activate``): ``obstacles`` (MarkerArray, taken raw: serialized bytes), ``terrain``
  (PointCloud2) and
  ``robot_description`` (String, arm), reliable depth 1, transient_local (``map_subscribe_transient_local``
  true, the default) or volatile (false: hears volatile publishers too), with QoS override parameters;
  requests ``goal_pose`` (PoseStamped: the helicopter's goal, or the arm's end-effector goal position) and
  ``goal_joints`` (JointState, arm), reliable; the robot's state ``odom`` (Odometry, helicopter) and
  ``joint_states`` (JointState, arm), best effort;
- services ``get_plan`` (``nav_msgs/srv/GetPlan``: as ``goal_pose``, from ``start`` when its frame is set)
  and ``replan`` (``std_srvs/srv/Trigger``: the published plan's goal again, from the robot's state now);
  Nav2's ``compute_path_to_pose`` action and ``is_path_valid`` service (:mod:`drd_planner.ros.nav2_host`);
  MoveIt's ``monitored_planning_scene`` topic and ``plan_kinematic_path`` service, arm
  (:mod:`drd_planner.ros.moveit_host`);
- publications: ``plan`` (Path, transient_local: the helicopter path, or the arm's end-effector path),
  ``joint_trajectory`` (JointTrajectory, transient_local, arm), ``edge_checks`` (DiagnosticArray, one
  status per check) and ``checked_edges`` (MarkerArray) are lifecycle publishers (silent until
  ``activate``, :mod:`drd_planner.ros.outputs`); ``/diagnostics`` in every state: one summary per plan,
  re-check, accepted map or error (statuses ``<node name>: plan`` / ``map update`` / ``maps`` / ``node``)
  and a 1 Hz ``<node name>: heartbeat``.

Parameters: :mod:`drd_planner.ros.parameters` (each with its description and range; ``planner_node
--help`` lists them). Each file in ``prior_paths`` (or its deprecated alias ``tree_paths``) is a world
prior (a tree file is a prior of its one query) served by a :class:`~drd_planner.planning.session.QuerySession`;
a request goes to the prior of its domain and is planned from the robot's state to its goal
(:mod:`drd_planner.planning.requests`).

The node keeps the lifecycle, the parameters and the ROS I/O. Maps, requests, coalescing, planning and
replanning after map updates are the :class:`~drd_planner.planning.service.PlannerService`'s (ROS-free; its
module docstring states the consistency rules), shared with the bag tools and ``drd plan --bag``: topic
requests are planned in the node's planning thread (:mod:`drd_planner.ros.plan_worker`), service calls in
their callback, one plan at a time; a plan whose edges a map update blocks is replanned (the reason on
``/diagnostics``) or withdrawn (an empty Path). A bad message or request is reported on ``/diagnostics`` and
in the log; no input ends the node (:mod:`drd_planner.ros.guard`), and no plan is published unless every one
of its edges was checked free on the snapshot it was planned on.
"""

from __future__ import annotations

import threading
import time
from collections import Counter
from collections.abc import Callable
from typing import Any

from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry
from nav_msgs.msg import Path as PathMsg
from nav_msgs.srv import GetPlan
from rcl_interfaces.msg import SetParametersResult
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.parameter import Parameter
from rclpy.qos_overriding_options import QoSOverridingOptions
from sensor_msgs.msg import JointState, PointCloud2
from std_msgs.msg import String
from std_srvs.srv import Trigger
from visualization_msgs.msg import MarkerArray

from drd_msgs_py.exceptions import MessageError
from drd_planner.exceptions import DrdError
from drd_planner.planner.prior_file import load_prior
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.requests import ambiguity, goal_from_pose, read_goal
from drd_planner.planning.service import LiveSettings, PlannerService, PlanRecord
from drd_planner.planning.session import QuerySession
from drd_planner.planning.session_plan import SessionPlan
from drd_planner.planning.shipped import resolve_tree_path
from drd_planner.ros.guard import guard_callback, guard_change_state, guard_service, shorten, traceback_of
from drd_planner.ros.moveit_host import MoveItHost
from drd_planner.ros.nav2_host import Nav2Host
from drd_planner.ros.outputs import LATCHED, PlannerOutputs
from drd_planner.ros.parameters import (
    PARAMETERS,
    check_cost_of,
    declare_parameters,
    goal_tolerances_of,
    map_limits_of,
    parameter_problems,
    plan_budgets_of,
    prior_paths_of,
)
from drd_planner.ros.plan_worker import PlanWorker
from drd_planner.ros.reporter import NodeReporter
from drd_planner.ros.status import HEARTBEAT_PERIOD_S, heartbeat_values, map_values
from drd_planner.ros.subscription_qos import REQUESTS, ROBOT_STATE, VOLATILE_MAPS

__all__ = ["LATCHED", "REQUESTS", "PlanRecord", "PlannerNode"]


#: Seconds between two reports of the same refused robot-state message (odometry streams fast).
STATE_ERROR_PERIOD_S = 5.0
#: Seconds :meth:`PlannerNode.destroy_node` waits for a running plan.
SHUTDOWN_WAIT_S = 1.0
#: What a refused map message leaves unchanged, per map topic.
_UNCHANGED = {
    "obstacles": "map unchanged",
    "terrain": "map unchanged",
    "robot_description": "the arm model is unchanged",
    "monitored_planning_scene": "map unchanged",
}


class PlannerNode(LifecycleNode):
    """See the module docstring."""

    def __init__(self, *, node_name: str = "drd_planner", **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        declare_parameters(self)
        self._service: PlannerService | None = None
        self._last_state_error: tuple[str, float] | None = None
        self._frame = "map"
        self._subs: list[Any] = []
        self._ros_services: list[Any] = []
        self._nav2: Nav2Host | None = None  # Nav2's planner interface, while active
        self._moveit: MoveItHost | None = None  # MoveIt's scene topic and plan_kinematic_path, while active
        self._lock = threading.Lock()  # the error list
        self._worker = PlanWorker(self._serve, on_error=self._on_worker_error)
        self._taken: Counter[str] = Counter()  # messages taken per subscribed topic
        self._out = PlannerOutputs(self)  # lifecycle publishers; /diagnostics in every state
        self._reporter = NodeReporter(self.get_logger(), self._out, self._report_error, self._report_bug)
        self._errors: list[str] = []
        self.add_on_set_parameters_callback(self._on_set_parameters)
        guard_change_state(self, report=self._report_to("node"))
        self._heartbeat = self.create_timer(
            HEARTBEAT_PERIOD_S,
            guard_callback(self._on_heartbeat, name="heartbeat", report=self._report_to("node")),
        )

    # ------------------------------------------------------------------------------------------------
    # Introspection (tests, diagnostics)

    @property
    def service(self) -> PlannerService | None:
        """The planner service (None until ``configure``, and after ``cleanup``)."""
        return self._service

    @property
    def sessions(self) -> tuple[QuerySession, ...]:
        """The loaded priors (a tree file loads as a prior of one tree)."""
        return self._service.sessions if self._service is not None else ()

    @property
    def snapshot(self) -> MapSnapshot:
        """The current maps."""
        return self._service.snapshot if self._service is not None else MapSnapshot(0)

    @property
    def published(self) -> SessionPlan | None:
        """The plan currently on ``plan`` (None: none, or it was withdrawn)."""
        published = self._service.published if self._service is not None else None
        return published.result if published is not None else None

    @property
    def planning_idle(self) -> bool:
        """True when the planning thread has served every request and map wake-up so far."""
        return self._worker.idle

    @property
    def inputs_taken(self) -> int:
        """Messages its subscriptions (maps, robot state, requests) have taken so far, accepted or refused."""
        return sum(self._taken.values())

    @property
    def history(self) -> tuple[PlanRecord, ...]:
        """The last served requests (:data:`~drd_planner.planning.service.HISTORY_LENGTH`), oldest first."""
        return self._service.history if self._service is not None else ()

    @property
    def errors(self) -> tuple[str, ...]:
        """Every error reported so far (also on ``/diagnostics``), oldest first; at most 100 kept."""
        return tuple(self._errors)

    # ------------------------------------------------------------------------------------------------
    # Lifecycle

    def _parameter(self, name: str) -> Any:
        return self.get_parameter(name).value

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Load the priors named in ``prior_paths``; any bad file fails the transition with its reason.

        The deprecated alias ``tree_paths`` is read while ``prior_paths`` is left at its default (with one
        warning naming ``prior_paths``); both set fails the transition.
        """
        values = {spec.name: self._parameter(spec.name) for spec in PARAMETERS}
        problems = parameter_problems(values)
        if problems:
            self._report_error(f"configure: invalid parameters: {'; '.join(problems)}", topic="node")
            return TransitionCallbackReturn.FAILURE
        try:
            names, deprecation = prior_paths_of(values)
        except ValueError as exc:
            self._report_error(f"configure: {exc}", topic="node")
            return TransitionCallbackReturn.FAILURE
        if deprecation is not None:
            self.get_logger().warning(deprecation)
        try:
            sessions = self._load_sessions(names, values)
        except DrdError as exc:
            self._report_error(f"configure: {exc}", topic="node")
            return TransitionCallbackReturn.FAILURE
        self._frame = str(self._parameter("frame_id"))
        self._out.frame = self._frame
        self._service = PlannerService(
            sessions,
            self._reporter,
            frame_id=self._frame,
            limits=map_limits_of(values),
            tolerances=goal_tolerances_of(values),
            live=self._live_settings,
            wake=self._worker.wake,
        )
        self.get_logger().info(f"loaded {len(sessions)} prior(s): {', '.join(s.name for s in sessions)}")
        return TransitionCallbackReturn.SUCCESS

    def _load_sessions(self, names: list[str], values: dict[str, Any]) -> list[QuerySession]:
        """One prior per file of ``names`` (DrdError: none named, a bad file, or priors that disagree)."""
        if not names:
            raise DrdError("parameter prior_paths names no prior file")
        budgets = plan_budgets_of(values)  # max_checks, time_budget_s, improve_budget
        check_cost = check_cost_of(values)
        sessions = []
        for name in names:
            path = resolve_tree_path(name)
            session = QuerySession(load_prior(path), name=path.stem, **budgets)
            if check_cost is not None:
                session.set_check_cost_ms(check_cost)
            sessions.append(session)
        ambiguous = ambiguity(sessions)
        if ambiguous is not None:
            raise DrdError(ambiguous)
        margins = {s.margin for s in sessions}
        if len(margins) != 1:
            raise DrdError(f"the priors use different collision margins {sorted(margins)}")
        return sessions

    def _live_settings(self) -> LiveSettings:
        """The parameters the service reads at each use (they may change while the node runs)."""
        return LiveSettings(
            seed=int(self._parameter("seed")),
            replan_on_map_update=bool(self._parameter("replan_on_map_update")),
            prior_start=str(self._parameter("start_without_robot_state")) == "prior_start",
            state_topics=(str(self._parameter("odom_topic")), str(self._parameter("joint_states_topic"))),
        )

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Enable the publishers, start the planning thread, subscribe to maps and requests, offer ``get_plan``."""
        enabled = super().on_activate(state)
        if enabled != TransitionCallbackReturn.SUCCESS:
            return enabled
        self._worker.start()
        maps = LATCHED if bool(self._parameter("map_subscribe_transient_local")) else VOLATILE_MAPS
        topics = [
            (MarkerArray, "obstacles", self._map_callback("obstacles"), maps, "maps"),
            (PointCloud2, "terrain", self._map_callback("terrain"), maps, "maps"),
            (String, "robot_description", self._map_callback("robot_description"), maps, "maps"),
            (PoseStamped, "goal_pose", self._request_callback("goal_pose"), REQUESTS, "plan"),
            (JointState, "goal_joints", self._request_callback("goal_joints"), REQUESTS, "plan"),
            (Odometry, str(self._parameter("odom_topic")), self._state_callback("odom"), ROBOT_STATE, "plan"),
            (
                JointState,
                str(self._parameter("joint_states_topic")),
                self._state_callback("joint_states"),
                ROBOT_STATE,
                "plan",
            ),
        ]
        self._subs = [
            self.create_subscription(
                kind,
                name,
                guard_callback(callback, name=name, report=self._report_to(topic), taken=self._taken),
                qos,
                qos_overriding_options=QoSOverridingOptions.with_default_policies(),
                raw=kind is MarkerArray,  # serialized: read in one pass, unchanged markers kept (map_store)
            )
            for kind, name, callback, qos, topic in topics
        ]
        report = self._report_to("plan")
        self._ros_services = [
            self.create_service(kind, name, guard_service(callback, name=name, report=report), qos_profile=REQUESTS)
            for kind, name, callback in (
                (GetPlan, "get_plan", self._on_get_plan),
                (Trigger, "replan", self._on_replan),
            )
        ]
        self._nav2 = None if self._service is None else Nav2Host.start(self, self._service, report=report)
        scenes = self._map_callback("monitored_planning_scene")
        on_scene = guard_callback(scenes, name="monitored_planning_scene", report=self._report_to("maps"))
        self._moveit = (
            None if self._service is None else MoveItHost.start(self, self._service, on_scene=on_scene, report=report)
        )
        durability = "transient_local" if maps is LATCHED else "volatile"
        self.get_logger().info(
            f"active: maps on {', '.join(sub.topic_name for sub in self._subs[:3])} ({durability}); "
            f"requests on {', '.join(sub.topic_name for sub in self._subs[3:5])}, "
            f"{' and '.join(service.srv_name for service in self._ros_services)}; "
            f"robot state on {', '.join(sub.topic_name for sub in self._subs[5:])}"
        )
        return TransitionCallbackReturn.SUCCESS

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Stop listening and publishing (maps are kept)."""
        self._drop_interfaces()
        return super().on_deactivate(state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Forget the priors and the maps."""
        self._drop_interfaces()
        self._service = None
        self._out.forget()
        return TransitionCallbackReturn.SUCCESS

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Release everything."""
        self._drop_interfaces()
        return TransitionCallbackReturn.SUCCESS

    def destroy_node(self) -> None:
        """Stop the planning thread (a plan running after :data:`SHUTDOWN_WAIT_S` is abandoned), destroy the node."""
        self._worker.stop(timeout=SHUTDOWN_WAIT_S)
        self._nav2 = self._nav2.stop() if self._nav2 is not None else None
        self._moveit = self._moveit.stop() if self._moveit is not None else None
        super().destroy_node()

    def _drop_interfaces(self) -> None:
        self._nav2 = self._nav2.stop() if self._nav2 is not None else None  # its running plans cancelled
        self._moveit = self._moveit.stop() if self._moveit is not None else None
        if not self._worker.stop():
            self.get_logger().warning("the planning thread did not end within 30 s")
        for sub in self._subs:
            self.destroy_subscription(sub)
        self._subs = []
        for service in self._ros_services:
            self.destroy_service(service)
        self._ros_services = []

    # ------------------------------------------------------------------------------------------------
    # Maps, robot state and requests in

    def _map_callback(self, source: str) -> Callable[[Any], None]:
        return lambda msg: self._on_map(source, msg)

    def _on_map(self, source: str, msg: Any) -> None:
        """Hand a map message to the service; log and report what it made of it."""
        assert self._service is not None  # subscriptions exist only while configured
        try:
            snapshot = self._service.take_map(source, msg, on_accept=lambda snap: self._log_accepted(source, snap))
        except (MessageError, DrdError) as exc:
            self._report_error(f"{source} refused, {_UNCHANGED[source]}: {exc}", topic="maps")
            return
        if snapshot is None:
            self.get_logger().info(f"{source} ignored: no arm prior is loaded")

    def _log_accepted(self, source: str, snapshot: MapSnapshot) -> None:
        """Log and report an accepted map version (before anything is re-checked against it)."""
        values = map_values(snapshot)
        self.get_logger().info(
            f"{source} accepted: map version {snapshot.version} ("
            + ", ".join(f"{k} {v}" for k, v in values.items() if k != "map_version")
            + ")"
        )
        self._out.status("maps", ok=True, message=f"{source} accepted", values={"source": source, **values})

    def _state_callback(self, kind: str) -> Callable[[Any], None]:
        return lambda msg: self._on_robot_state(kind, msg)

    def _on_robot_state(self, kind: str, msg: Any) -> None:
        assert self._service is not None
        try:
            self._service.take_robot_state(kind, msg)
        except (MessageError, DrdError) as exc:
            what = "odometry" if kind == "odom" else kind
            self._report_state_error(f"{what} refused, robot state unchanged: {exc}")

    def _report_state_error(self, text: str) -> None:
        """Report a refused robot state at most once per :data:`STATE_ERROR_PERIOD_S` for the same text (streams)."""
        now = time.monotonic()
        last = self._last_state_error
        if last is not None and last[0] == text and now - last[1] < STATE_ERROR_PERIOD_S:
            return
        self._last_state_error = (text, now)
        self._report_error(text)

    def _request_callback(self, source: str) -> Callable[[Any], None]:
        return lambda msg: self._on_request(source, msg)

    def _on_request(self, source: str, msg: Any) -> None:
        """A ``goal_pose`` or ``goal_joints`` message: parsed, then queued for the planning thread."""
        assert self._service is not None
        try:
            goal = read_goal(source, msg, self._service.sessions, self._frame)
        except (MessageError, DrdError) as exc:
            self._report_error(f"{source} refused: {exc}")
            return
        stamp = msg.header.stamp
        self._service.enqueue(goal, source, f"{int(stamp.sec)}.{int(stamp.nanosec):09d}")

    def _serve(self) -> None:
        """The planning thread's work: the service's pending requests and re-checks."""
        if self._service is not None:
            self._service.serve()

    def _on_get_plan(self, request: Any, response: Any) -> Any:
        result = self.plan_for(request.goal, request.start)
        response.plan = result if result is not None else PathMsg()
        return response

    def plan_for(self, goal: Any, start: Any = None) -> Any | None:
        """Serve one ``get_plan`` (PoseStamped ``goal``; ``start``, if its frame is set): the Path, or None."""
        service = self._service
        if service is None:
            self._report_error("get_plan refused: the node is not configured")
            return None
        try:
            parsed = goal_from_pose(goal, self._frame)
            given = None
            if start is not None and str(start.header.frame_id):
                given = goal_from_pose(start, self._frame, "start")
        except (MessageError, DrdError) as exc:
            self._report_error(f"get_plan refused: {exc}")
            return None
        sent = service.plan_now(parsed, given)  # published as bytes; the response needs the message
        return None if sent is None else sent.path()

    def _on_replan(self, request: Any, response: Any) -> Any:
        """``replan`` (std_srvs/Trigger): plan again to the published plan's goal from the robot's state now."""
        errors = self._errors  # replaced by a new list on every report
        path, had_plan = self._service.replan() if self._service is not None else (None, False)
        if not had_plan:
            response.success, response.message = False, "no plan is published: nothing to replan"
            return response
        response.success = path is not None
        if path is not None:
            response.message = "replanned"
        elif self._errors is not errors:
            response.message = f"no new plan: {self._errors[-1]}"
        else:
            response.message = "no new plan: see the plan summary on /diagnostics"
        return response

    # ------------------------------------------------------------------------------------------------
    # Reports

    def _on_worker_error(self, exc: Exception) -> None:
        self._report_bug(f"internal error while planning (the node goes on): {type(exc).__name__}: {exc}", exc)

    def _report_bug(self, text: str, exc: BaseException) -> None:
        """:meth:`_report_error` of a bug: the log line (ERROR) is followed by ``exc``'s traceback."""
        self._report_error(text, "plan", trace=traceback_of(exc))

    def _report_to(self, topic: str) -> Callable[[str], None]:
        """:meth:`_report_error` under the status ``topic``."""
        return lambda text: self._report_error(text, topic)

    def _on_heartbeat(self) -> None:
        service = self._service
        with self._lock:
            errors = len(self._errors)
        values = heartbeat_values(
            state=str(self._state_machine.current_state[1]),
            snapshot=self.snapshot,
            priors=len(self.sessions),
            published=service is not None and service.published is not None,
            pending=service.pending if service is not None else 0,
            errors=errors,
            last=self._reporter.last_plan,
            now=time.monotonic(),
        )
        maps = "known" if values["maps_known"] else "not received yet"
        self._out.status("heartbeat", ok=True, message=f"{values['state']}, maps {maps}", values=values)

    def _on_set_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        """Refuse a runtime parameter change that fails its check (the old value stays), with the reason."""
        problems = parameter_problems({p.name: p.value for p in parameters})
        if problems:
            reason = shorten("; ".join(problems))
            self.get_logger().warning(f"parameter change refused: {reason}")
            return SetParametersResult(successful=False, reason=reason)
        return SetParametersResult(successful=True)

    def _report_error(self, text: str, topic: str = "plan", *, trace: str = "") -> None:
        """Log ``text`` (shortened; then ``trace``, a traceback), keep it, put it on ``/diagnostics`` (``topic``)."""
        text = shorten(text)
        self.get_logger().error(f"{text}\n{trace}" if trace else text)
        with self._lock:
            self._errors = [*self._errors[-99:], text]
        self._out.status(topic, ok=False, message=text, values={})
