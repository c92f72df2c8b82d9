"""The ``drd_planner`` lifecycle node (rclpy): maps and the robot's state in, lazily checked plans out.

Interface (DESIGN.md section 6; names relative to the node namespace):

- subscriptions (after ``activate``): ``obstacles`` (MarkerArray), ``terrain`` (PointCloud2) and
  ``robot_description`` (String, arm), reliable depth 1, transient_local (``map_subscribe_transient_local``
  true, the default) or volatile (false: hears volatile publishers too), with QoS override parameters;
  requests ``goal_pose`` (PoseStamped: the helicopter's goal, or the arm's end-effector goal position) and
  ``goal_joints`` (JointState, arm), reliable; the robot's state ``odom`` (Odometry, helicopter) and
  ``joint_states`` (JointState, arm), best effort;
- services ``get_plan`` (``nav_msgs/srv/GetPlan``: as ``goal_pose``, from ``start`` when its frame is set)
  and ``replan`` (``std_srvs/srv/Trigger``: the published plan's goal again, from the robot's state now);
- publications: ``plan`` (Path, transient_local: the helicopter path, or the arm's end-effector path),
  ``joint_trajectory`` (JointTrajectory, transient_local, arm), ``edge_checks`` (DiagnosticArray, one
  status per check) and ``checked_edges`` (MarkerArray) are lifecycle publishers (silent until
  ``activate``, :mod:`drd_planner.ros.outputs`); ``/diagnostics`` in every state: one summary per plan,
  re-check, accepted map or error (statuses ``<node name>: plan`` / ``map update`` / ``maps`` / ``node``)
  and a 1 Hz ``<node name>: heartbeat``.

Parameters: :mod:`drd_planner.ros.parameters` (each with its description and range; ``planner_node
--help`` lists them). Each file in ``tree_paths`` is a world prior (a tree file is a prior of its one
query) served by a :class:`~drd_planner.planning.query_session.QuerySession`; a request goes to the prior
of its domain and is planned from the robot's state to its goal (:mod:`drd_planner.planning.requests`).

Consistency. Maps and requests arrive in executor callbacks; topic requests are planned in the node's
planning thread (:mod:`drd_planner.ros.plan_worker`), service calls in their callback, one plan at a
time. A plan runs to its end on the map snapshot it started from; a map that arrives meanwhile makes a
new snapshot (its FCL scene and checkers built in the map callback) that the next plan uses. Topic
requests are *coalesced*: while a plan runs, a newer request for the same prior supersedes an older
one that has not started (the summary's ``coalesced`` value counts them); service calls are each
answered. Every map that arrives before a plan is published, or after, is compared with the map that
plan was verified on; only the plan's edges the update can affect are re-checked
(:mod:`drd_planner.planning.replan`): the plan is kept if they stay free, replanned from the robot's
state now (and the reason put on ``/diagnostics``) if one is blocked, and withdrawn (an empty Path) if
no free path is found. A bad message or request is reported on ``/diagnostics`` and in the log; no
input ends the node (:mod:`drd_planner.ros.guard`), and no plan is published unless every one of its
edges was checked free on the snapshot it was planned on.
"""

from __future__ import annotations

import dataclasses
import sys
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import rclpy
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry
from nav_msgs.msg import Path as PathMsg
from nav_msgs.srv import GetPlan
from rcl_interfaces.msg import SetParametersResult
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.qos_overriding_options import QoSOverridingOptions
from rclpy.utilities import try_shutdown
from sensor_msgs.msg import JointState, PointCloud2
from std_msgs.msg import String
from std_srvs.srv import Trigger
from visualization_msgs.msg import MarkerArray

from drd_msgs_py.exceptions import MessageError
from drd_msgs_py.obstacles import obstacle_update
from drd_msgs_py.terrain import heightfield_from_cloud
from drd_planner.arrays import FloatArray
from drd_planner.exceptions import DrdError, PlanningError
from drd_planner.planner.endpoints import Endpoint
from drd_planner.planner.prior_file import load_prior
from drd_planner.planning.map_limits import MapLimits
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.query_session import QueryPlanResult, QuerySession
from drd_planner.planning.query_support import state_from_pose
from drd_planner.planning.replan import recheck_plan
from drd_planner.planning.requests import (
    Goal,
    ambiguity,
    goal_endpoint,
    goal_from_pose,
    joint_vector,
    pick_session,
    start_from_odometry,
)
from drd_planner.planning.session import PlanResult
from drd_planner.planning.shipped import resolve_tree_path
from drd_planner.ros.guard import guard_callback, guard_change_state, guard_service, shorten
from drd_planner.ros.outputs import LATCHED, PlannerOutputs, plan_summary_values
from drd_planner.ros.parameters import PARAMETERS, declare_parameters, map_limits_of, parameter_problems
from drd_planner.ros.plan_worker import PlanWorker
from drd_planner.ros.status import HEARTBEAT_PERIOD_S, LastPlan, heartbeat_values, map_values

__all__ = ["LATCHED", "REQUESTS", "PlanRecord", "PlannerNode", "main"]


#: Map subscriptions with ``map_subscribe_transient_local`` false: hears volatile and latched publishers.
VOLATILE_MAPS = QoSProfile(
    depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE
)
#: The robot's state (odometry, joint states): best effort, which hears reliable publishers too.
ROBOT_STATE = QoSProfile(depth=5, reliability=ReliabilityPolicy.BEST_EFFORT)
#: Requests (topics and the service): reliable and deep enough that a burst reaches the node, which then
#: coalesces it (with KEEP_LAST 10 the middleware would drop all but the last 10 unseen).
REQUESTS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)

#: Served requests kept in :attr:`PlannerNode.history`.
HISTORY_LENGTH = 16
#: The newest records of the history that keep their map snapshot (older ones drop it: a snapshot
#: holds its terrain heightfield, up to 2 MB at the default ``max_terrain_cells``, and obstacle parts;
#: FCL scenes live in ``planning.map_state``'s own bounded cache). 8 covers the bundled bags' plans.
SNAPSHOTS_KEPT = 8
#: Seconds between two reports of the same refused robot-state message (odometry streams fast).
STATE_ERROR_PERIOD_S = 5.0
#: Seconds :meth:`PlannerNode.destroy_node` waits for a running plan.
SHUTDOWN_WAIT_S = 1.0
#: Longest executor wait (seconds) of ``planner_node``'s spin loop.
SPIN_TIMEOUT_S = 0.25


@dataclass(frozen=True)
class _Request:
    """A goal waiting to be planned: the prior that serves it, the goal, the start, where it came from."""

    session: QuerySession
    goal: Goal
    start: FloatArray | None  # None: the robot's state when the plan starts
    source: str
    stamp: str
    coalesced: int = 0
    received: float = 0.0  # time.perf_counter() when the request was taken


@dataclass(frozen=True)
class PlanRecord:
    """One served request, as kept in :attr:`PlannerNode.history`.

    Attributes:
        session: the prior that planned it.
        result: the plan (or why there is none) with its check log.
        snapshot: the maps it was planned on (None once :data:`SNAPSHOTS_KEPT` newer records exist).
        request: where it came from (``goal_pose``, ``goal_joints``, ``get_plan``, ``map_update``) and the
            other summary values of the request.
    """

    session: QuerySession
    result: QueryPlanResult
    snapshot: MapSnapshot | None
    request: dict[str, Any]


@dataclass(frozen=True)
class _Published:
    """The plan on ``plan`` now: what a map update must re-check, and its goal for a replan."""

    session: QuerySession
    result: PlanResult
    snapshot: MapSnapshot
    goal: Goal


class PlannerNode(LifecycleNode):
    """See the module docstring."""

    def __init__(self, *, node_name: str = "drd_planner", **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        declare_parameters(self)
        self._sessions: list[QuerySession] = []
        self._robot_states: dict[bool, FloatArray] = {}  # is_arm -> the latest robot state
        self._last_state_error: tuple[str, float] | None = None
        self._obstacles: dict[str, Any] = {}
        self._snapshot = MapSnapshot(0)
        self._frame = "map"
        self._subs: list[Any] = []
        self._service: Any = None
        self._replan_service: Any = None
        self._tolerances = (1.0, 0.05)
        self._lock = threading.Lock()  # the pending requests and the map-changed flag
        self._planning = threading.Lock()  # one plan at a time: the sessions' caches, the published plan
        self._pending: dict[str, _Request] = {}
        self._published: _Published | None = None
        self._worker = PlanWorker(self._serve, on_error=self._on_worker_error)
        self._out = PlannerOutputs(self)  # lifecycle publishers; /diagnostics in every state
        self._errors: list[str] = []
        self._history: deque[PlanRecord] = deque(maxlen=HISTORY_LENGTH)
        self._last_plan: LastPlan | None = None
        self._limits = MapLimits.DEFAULT
        self.add_on_set_parameters_callback(self._on_set_parameters)
        guard_change_state(self, report=self._reporter("node"))
        self._heartbeat = self.create_timer(
            HEARTBEAT_PERIOD_S,
            guard_callback(self._on_heartbeat, name="heartbeat", report=self._reporter("node")),
        )

    # ------------------------------------------------------------------------------------------------
    # Introspection (tests, diagnostics)

    @property
    def sessions(self) -> tuple[QuerySession, ...]:
        """The loaded priors (a tree file loads as a prior of one tree)."""
        return tuple(self._sessions)

    @property
    def snapshot(self) -> MapSnapshot:
        """The current maps."""
        return self._snapshot

    @property
    def published(self) -> PlanResult | None:
        """The plan currently on ``plan`` (None: none, or it was withdrawn)."""
        return self._published.result if self._published is not None else None

    @property
    def planning_idle(self) -> bool:
        """True when the planning thread has served every request and map wake-up so far."""
        return self._worker.idle

    @property
    def history(self) -> tuple[PlanRecord, ...]:
        """The last served requests (at most :data:`HISTORY_LENGTH`), oldest first."""
        return tuple(self._history)

    @property
    def errors(self) -> tuple[str, ...]:
        """Every error reported so far (also on ``/diagnostics``), oldest first; at most 100 kept."""
        return tuple(self._errors)

    # ------------------------------------------------------------------------------------------------
    # Lifecycle

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Load the trees named in ``tree_paths``; any bad file fails the transition with its reason."""
        problems = parameter_problems({spec.name: self.get_parameter(spec.name).value for spec in PARAMETERS})
        if problems:
            self._report_error(f"configure: invalid parameters: {'; '.join(problems)}", topic="node")
            return TransitionCallbackReturn.FAILURE
        self._limits = map_limits_of({spec.name: self.get_parameter(spec.name).value for spec in PARAMETERS})
        names = [p for p in self.get_parameter("tree_paths").value if p]
        self._frame = str(self.get_parameter("frame_id").value)
        self._out.frame = self._frame
        max_checks = int(self.get_parameter("max_checks").value)
        tolerance = float(self.get_parameter("goal_tolerance").value)
        joint_tolerance = float(self.get_parameter("joint_tolerance").value)
        if not names:
            self._report_error("configure: parameter tree_paths names no tree file", topic="node")
            return TransitionCallbackReturn.FAILURE
        budget = float(self.get_parameter("planning_time_budget").value)
        sessions = []
        for name in names:
            try:
                path = resolve_tree_path(name)
                sessions.append(
                    QuerySession(
                        load_prior(path),
                        name=path.stem,
                        max_checks=max_checks if max_checks > 0 else None,
                        time_budget_s=budget if budget > 0 else None,
                    )
                )
            except DrdError as exc:
                self._report_error(f"configure: {exc}", topic="node")
                return TransitionCallbackReturn.FAILURE
        ambiguous = ambiguity(sessions)
        if ambiguous is not None:
            self._report_error(f"configure: {ambiguous}", topic="node")
            return TransitionCallbackReturn.FAILURE
        margins = {s.margin for s in sessions}
        if len(margins) != 1:
            self._report_error(
                f"configure: the trees use different collision margins {sorted(margins)}", topic="node"
            )
            return TransitionCallbackReturn.FAILURE
        self._sessions = sessions
        self._obstacles, self._published, self._pending, self._robot_states = {}, None, {}, {}
        self._tolerances = (tolerance, joint_tolerance)
        self._snapshot = MapSnapshot(0, margin=margins.pop())
        self.get_logger().info(f"loaded {len(sessions)} tree(s): {', '.join(s.name for s in sessions)}")
        return TransitionCallbackReturn.SUCCESS

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Enable the publishers, start the planning thread, subscribe to maps and requests, offer ``get_plan``."""
        enabled = super().on_activate(state)
        if enabled != TransitionCallbackReturn.SUCCESS:
            return enabled
        self._worker.start()
        report = self._reporter("plan")
        maps = LATCHED if bool(self.get_parameter("map_subscribe_transient_local").value) else VOLATILE_MAPS
        topics = [
            (MarkerArray, "obstacles", self._on_obstacles, maps, "maps"),
            (PointCloud2, "terrain", self._on_terrain, maps, "maps"),
            (String, "robot_description", self._on_robot_description, maps, "maps"),
            (PoseStamped, "goal_pose", self._on_goal_pose, REQUESTS, "plan"),
            (JointState, "goal_joints", self._on_goal_joints, REQUESTS, "plan"),
            (Odometry, str(self.get_parameter("odom_topic").value), self._on_odometry, ROBOT_STATE, "plan"),
            (
                JointState,
                str(self.get_parameter("joint_states_topic").value),
                self._on_joint_states,
                ROBOT_STATE,
                "plan",
            ),
        ]
        self._subs = [
            self.create_subscription(
                kind,
                name,
                guard_callback(callback, name=name, report=self._reporter(topic)),
                qos,
                qos_overriding_options=QoSOverridingOptions.with_default_policies(),
            )
            for kind, name, callback, qos, topic in topics
        ]
        self._service = self.create_service(
            GetPlan,
            "get_plan",
            guard_service(self._on_get_plan, name="get_plan", report=report),
            qos_profile=REQUESTS,
        )
        self._replan_service = self.create_service(
            Trigger,
            "replan",
            guard_service(self._on_replan, name="replan", report=report),
            qos_profile=REQUESTS,
        )
        durability = "transient_local" if maps is LATCHED else "volatile"
        self.get_logger().info(
            f"active: maps on {', '.join(sub.topic_name for sub in self._subs[:3])} ({durability}); "
            f"requests on {', '.join(sub.topic_name for sub in self._subs[3:5])}, {self._service.srv_name} and "
            f"{self._replan_service.srv_name}; robot state on {', '.join(sub.topic_name for sub in self._subs[5:])}"
        )
        return TransitionCallbackReturn.SUCCESS

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Stop listening and publishing (maps are kept)."""
        self._drop_interfaces()
        return super().on_deactivate(state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Forget the trees and the maps."""
        self._drop_interfaces()
        self._sessions, self._obstacles, self._snapshot = [], {}, MapSnapshot(0)
        self._published, self._pending = None, {}
        self._out.forget()
        return TransitionCallbackReturn.SUCCESS

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Release everything."""
        self._drop_interfaces()
        return TransitionCallbackReturn.SUCCESS

    def destroy_node(self) -> None:
        """Stop the planning thread, then destroy the node.

        A plan still running after :data:`SHUTDOWN_WAIT_S` is abandoned (the thread is a daemon and
        publishes nothing once the node is gone), so SIGINT / SIGTERM end the process promptly.
        """
        self._worker.stop(timeout=SHUTDOWN_WAIT_S)
        super().destroy_node()

    def _drop_interfaces(self) -> None:
        if not self._worker.stop():
            self.get_logger().warning("the planning thread did not end within 30 s")
        for sub in self._subs:
            self.destroy_subscription(sub)
        self._subs = []
        for service in (self._service, self._replan_service):
            if service is not None:
                self.destroy_service(service)
        self._service = self._replan_service = None

    # ------------------------------------------------------------------------------------------------
    # Maps

    def _on_obstacles(self, msg: MarkerArray) -> None:
        try:
            update = obstacle_update(msg, frame_id=self._frame, limits=self._limits)
            obstacles = update.apply(self._obstacles)  # refuses a map that grows beyond a limit
        except MessageError as exc:
            self._report_error(f"obstacles refused, map unchanged: {exc}", topic="maps")
            return
        self._obstacles = obstacles
        self._set_snapshot(
            self._snapshot.with_obstacles({k: o.parts for k, o in self._obstacles.items()}), "obstacles"
        )

    def _on_terrain(self, msg: PointCloud2) -> None:
        try:
            terrain = heightfield_from_cloud(msg, frame_id=self._frame, limits=self._limits)
        except MessageError as exc:
            self._report_error(f"terrain refused, map unchanged: {exc}", topic="maps")
            return
        self._set_snapshot(self._snapshot.with_terrain(terrain), "terrain")

    def _on_robot_description(self, msg: String) -> None:
        arms = [s for s in self._sessions if s.is_arm]
        if not arms:
            self.get_logger().info("robot_description ignored: no arm tree is loaded")
            return
        try:
            robot = arms[0].domain.robot_from_description(  # type: ignore[attr-defined]
                str(msg.data), limits=self._limits
            )
        except DrdError as exc:
            self._report_error(f"robot_description refused, the arm model is unchanged: {exc}", topic="maps")
            return
        self._set_snapshot(self._snapshot.with_robot(robot), "robot_description")

    def _set_snapshot(self, snapshot: MapSnapshot, source: str) -> None:
        """Make ``snapshot`` (from a ``source`` message) current, log and report it; then re-check the plan.

        The wake-up is unconditional: a plan being made on an older snapshot right now is published
        after this, and must be re-checked against this map as well.
        """
        self._prepare(snapshot)
        self._snapshot = snapshot
        self._worker.wake()
        values = map_values(snapshot)
        self.get_logger().info(
            f"{source} accepted: map version {snapshot.version} ("
            + ", ".join(f"{k} {v}" for k, v in values.items() if k != "map_version")
            + ")"
        )
        self._out.status("maps", ok=True, message=f"{source} accepted", values={"source": source, **values})

    def _prepare(self, snapshot: MapSnapshot) -> None:
        """Build the new maps' FCL scene and each tree's checker now, not in the next request.

        Runs in the map callback, before the snapshot becomes current: a request served meanwhile plans
        on the previous snapshot, one served after starts checking at once. A failure here is only
        logged; the plan on this snapshot meets it again and reports it.
        """
        for session in self._sessions:
            try:
                seconds = session.prepare(snapshot)
            except Exception as exc:  # the plan on this snapshot meets it again
                self.get_logger().warning(
                    shorten(f"{session.name}: map version {snapshot.version} not prepared: {exc}")
                )
                continue
            self.get_logger().debug(
                f"{session.name}: map version {snapshot.version} prepared in {1e3 * seconds:.1f} ms"
            )

    # ------------------------------------------------------------------------------------------------
    # Requests

    def _on_goal_pose(self, msg: PoseStamped) -> None:
        try:
            goal = goal_from_pose(msg, self._frame, "goal_pose")
        except (MessageError, DrdError) as exc:
            self._report_error(f"goal_pose refused: {exc}")
            return
        self._enqueue(goal, "goal_pose", msg.header.stamp)

    def _on_goal_joints(self, msg: JointState) -> None:
        arms = [s for s in self._sessions if s.is_arm]
        if not arms:
            self._report_error("goal_joints refused: no arm prior is loaded")
            return
        try:
            goal = Goal(joints=joint_vector(msg, arms[0].joint_names, "goal_joints"))
        except MessageError as exc:
            self._report_error(f"goal_joints refused: {exc}")
            return
        self._enqueue(goal, "goal_joints", msg.header.stamp)

    def _on_odometry(self, msg: Any) -> None:
        try:
            state = start_from_odometry(msg, self._frame)
        except (MessageError, DrdError) as exc:
            self._report_state_error(f"odometry refused, robot state unchanged: {exc}")
            return
        self._robot_states[False] = state

    def _on_joint_states(self, msg: JointState) -> None:
        arms = [s for s in self._sessions if s.is_arm]
        if not arms:
            return  # a helicopter stack's joint states are not ours
        try:
            self._robot_states[True] = joint_vector(msg, arms[0].joint_names)
        except MessageError as exc:
            self._report_state_error(f"joint_states refused, robot state unchanged: {exc}")

    def _report_state_error(self, text: str) -> None:
        """Report a refused robot state, at most once per :data:`STATE_ERROR_PERIOD_S` for the same text.

        Odometry and joint states stream at tens of Hz; a stream in the wrong frame would otherwise
        flood the log and ``/diagnostics``.
        """
        now = time.monotonic()
        last = self._last_state_error
        if last is not None and last[0] == text and now - last[1] < STATE_ERROR_PERIOD_S:
            return
        self._last_state_error = (text, now)
        self._report_error(text)

    def _enqueue(self, goal: Goal, source: str, stamp: Any) -> None:
        session = pick_session(self._sessions, goal)
        if session is None:
            self._report_error(f"{source} refused: no loaded prior plans for {goal.describe()}")
            return
        stamp_text = f"{int(stamp.sec)}.{int(stamp.nanosec):09d}"
        with self._lock:
            older = self._pending.get(session.name)
            coalesced = older.coalesced + 1 if older is not None else 0
            self._pending[session.name] = _Request(
                session, goal, None, source, stamp_text, coalesced, received=time.perf_counter()
            )
        self._worker.wake()

    def _serve(self) -> None:
        """Plan the newest pending request of each tree, then re-check the published plan if maps changed."""
        with self._planning:
            self._serve_pending()

    def _serve_pending(self) -> None:
        with self._lock:
            pending, self._pending = list(self._pending.values()), {}
        for request in pending:
            self._plan_and_publish(
                request.session,
                request.goal,
                request.start,
                {"request": request.source, "request_stamp": request.stamp, "coalesced": request.coalesced},
                wait_s=time.perf_counter() - request.received,
            )
        published = self._published
        if published is not None and published.snapshot is not self._snapshot:
            try:
                self._recheck(published)  # every map that arrived before the plan was published, or since
            except Exception:
                self._withdraw(published.session, self._snapshot, why="its re-check failed")
                raise

    def _on_get_plan(self, request: Any, response: Any) -> Any:
        result = self.plan_for(request.goal, request.start)
        response.plan = result if result is not None else PathMsg()
        return response

    def plan_for(self, goal: Any, start: Any = None) -> Any | None:
        """Serve one ``get_plan`` now: the published Path, or None (the reason went to ``/diagnostics``).

        Args:
            goal: the goal PoseStamped.
            start: a PoseStamped start (helicopter); None or an empty ``frame_id``: the robot's state.
        """
        try:
            parsed = goal_from_pose(goal, self._frame)
            given = None
            if start is not None and str(start.header.frame_id):
                given = goal_from_pose(start, self._frame, "start")
        except (MessageError, DrdError) as exc:
            self._report_error(f"get_plan refused: {exc}")
            return None
        session = pick_session(self._sessions, parsed)
        if session is None:
            self._report_error(f"get_plan refused: no loaded prior plans for {parsed.describe()}")
            return None
        start_state = None
        if given is not None:
            if session.is_arm:
                self._report_error("get_plan refused: an arm's start comes from joint_states, not a pose")
                return None
            assert given.position is not None
            start_state = state_from_pose(given.position, given.yaw)
        received = time.perf_counter()
        with self._planning:
            path = self._plan_and_publish(
                session, parsed, start_state, {"request": "get_plan"}, wait_s=time.perf_counter() - received
            )
        self._worker.wake()  # re-check it if a map arrived while it was planned
        return path

    def _on_replan(self, request: Any, response: Any) -> Any:
        """``replan`` (std_srvs/Trigger): plan again to the published plan's goal from the robot's state now."""
        published = self._published
        if published is None:
            response.success, response.message = False, "no plan is published: nothing to replan"
            return response
        errors = self._errors  # replaced by a new list on every report
        with self._planning:
            path = self._plan_and_publish(published.session, published.goal, None, {"request": "replan"})
        self._worker.wake()
        response.success = path is not None
        if path is not None:
            response.message = "replanned"
        elif self._errors is not errors:
            response.message = f"no new plan: {self._errors[-1]}"
        else:
            response.message = "no new plan: see the plan summary on /diagnostics"
        return response

    def _start_for(self, session: QuerySession) -> Endpoint:
        """Where a plan of ``session`` starts when the request gives no start: the robot's state."""
        state = self._robot_states.get(session.is_arm)
        if state is not None:
            return state
        if str(self.get_parameter("start_without_robot_state").value) == "prior_start":
            return int(session.domain.start)
        topic = self.get_parameter("joint_states_topic" if session.is_arm else "odom_topic").value
        raise PlanningError(
            f"no robot state known yet: nothing received on {topic!r} (give get_plan a start, or set "
            "start_without_robot_state to prior_start to plan from the prior's stored start)"
        )

    def _plan_and_publish(
        self,
        session: QuerySession,
        goal: Goal,
        start: FloatArray | None,
        values: dict[str, Any],
        *,
        wait_s: float = 0.0,
    ) -> Any | None:
        """Plan on the current snapshot and publish; ``wait_s``: how long the request waited to be served."""
        snapshot = self._snapshot
        tolerance, joint_tolerance = self._tolerances
        try:
            begin = start if start is not None else self._start_for(session)
            end = goal_endpoint(session, goal, snapshot, tolerance=tolerance, joint_tolerance=joint_tolerance)
            result = session.plan(snapshot, begin, end, seed=int(self.get_parameter("seed").value))
        except DrdError as exc:
            self._report_error(f"{values.get('request', 'request')} refused: {exc}")
            return None
        # A start or goal the prior cannot serve is a refused request, not a plan.
        if result.status == "refused":
            self._report_error(f"{values.get('request', 'request')} refused: {result.message}")
            return None
        return self._publish(session, result, snapshot, values, goal, wait_s=wait_s)

    # ------------------------------------------------------------------------------------------------
    # Map updates after a published plan

    def _recheck(self, published: _Published) -> None:
        snapshot = self._snapshot
        session = published.session
        try:
            outcome = recheck_plan(session, published.result.path_edges, published.snapshot, snapshot)
        except DrdError as exc:
            reason = f"re-check after map update failed: {exc}"
            self._report_error(f"{reason}; replanning")
        else:
            if outcome.kept:
                self._published = _Published(session, published.result, snapshot, published.goal)
                self._out.status(
                    "map update",
                    ok=True,
                    message=outcome.reason,
                    values={
                        "tree": session.name,
                        "map_version": snapshot.version,
                        "affected": len(outcome.affected),
                        "rechecked": len(outcome.rechecked),
                        "check_s": f"{outcome.total_check_ms / 1e3:.6f}",
                        "selection_s": f"{outcome.select_ms / 1e3:.6f}",
                        "result": "plan_kept",
                    },
                )
                self.get_logger().info(outcome.reason)
                return
            reason = outcome.reason
            self.get_logger().warning(reason)
        if not bool(self.get_parameter("replan_on_map_update").value):
            self._withdraw(session, snapshot, why=f"{reason}; replan_on_map_update is false")
        elif (
            self._plan_and_publish(
                session, published.goal, None, {"request": "map_update", "replan_reason": reason}
            )
            is None
        ):
            self._withdraw(session, snapshot, why="no replacement was found")

    def _withdraw(self, session: QuerySession, snapshot: MapSnapshot, *, why: str) -> None:
        """Take the published plan back: it is no longer known free on the current maps."""
        if self._published is None:
            return
        self._published = None
        self._out.withdraw(session)
        self._report_error(
            f"{session.name}: the published plan is blocked on map version {snapshot.version} ({why}); "
            "published an empty plan"
        )

    # ------------------------------------------------------------------------------------------------
    # Publishing

    def _publish(
        self,
        session: QuerySession,
        result: QueryPlanResult,
        snapshot: MapSnapshot,
        extra: dict[str, Any],
        goal: Goal,
        *,
        wait_s: float = 0.0,
    ) -> Any | None:
        """Publish a result: ``plan`` (and ``joint_trajectory``) first, then the rest.

        After the plan come the check log, the markers and last the summary. Its timing values
        (seconds): ``check_s``, ``selection_s``, ``policy_s``, ``prepare_s`` and ``total_s`` of the plan
        (:class:`PlanResult`), ``wait_s`` (request taken -> served), ``plan_messaging_s`` (building and
        publishing ``plan``/``joint_trajectory``) and ``messaging_s`` (all messages before the summary).
        """
        started = time.perf_counter()
        stamp = self._out.stamp()
        self._remember(PlanRecord(session, result, snapshot, dict(extra)))
        path = self._publish_plan(session, result, snapshot, goal, stamp) if result.ok else None
        plan_messaging_s = time.perf_counter() - started
        self._out.checks(result, stamp)
        self._out.markers(session, result, snapshot, stamp)
        values = plan_summary_values(
            result,
            extra,
            wait_s=wait_s,
            plan_messaging_s=plan_messaging_s,
            messaging_s=time.perf_counter() - started,
        )
        self._last_plan = LastPlan(str(result.status), str(extra.get("request", "request")), time.monotonic())
        self._out.status("plan", ok=result.ok, message=result.message, values=values, stamp=stamp)
        if result.ok:
            self.get_logger().info(f"{result.tree}: {result.message}")
        else:
            self.get_logger().warning(f"{result.tree}: {result.message}; nothing published on plan")
        return path

    def _remember(self, record: PlanRecord) -> None:
        """Add ``record`` to the history; the record :data:`SNAPSHOTS_KEPT` back lets go of its snapshot."""
        self._history.append(record)
        if len(self._history) > SNAPSHOTS_KEPT:
            old = self._history[-SNAPSHOTS_KEPT - 1]
            if old.snapshot is not None:
                self._history[-SNAPSHOTS_KEPT - 1] = dataclasses.replace(old, snapshot=None)

    def _publish_plan(
        self,
        session: QuerySession,
        result: PlanResult,
        snapshot: MapSnapshot,
        goal: Goal,
        stamp: tuple[int, int],
    ) -> Any:
        """Publish a found plan on ``plan`` (and ``joint_trajectory`` for the arm); it becomes the published plan."""
        path = self._out.plan(session, result, snapshot, stamp)
        if self._out.active:  # an inactive node publishes nothing, so it has no plan out there
            self._published = _Published(session, result, snapshot, goal)
        return path

    def _on_worker_error(self, exc: Exception) -> None:
        self._report_error(f"internal error while planning (the node goes on): {type(exc).__name__}: {exc}")

    def _reporter(self, topic: str) -> Callable[[str], None]:
        """:meth:`_report_error` under the status ``topic``."""
        return lambda text: self._report_error(text, topic)

    def _on_heartbeat(self) -> None:
        with self._lock:
            pending = len(self._pending)
            errors = len(self._errors)
        values = heartbeat_values(
            state=str(self._state_machine.current_state[1]),
            snapshot=self._snapshot,
            trees=len(self._sessions),
            published=self._published is not None,
            pending=pending,
            errors=errors,
            last=self._last_plan,
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

    def _report_error(self, text: str, topic: str = "plan") -> None:
        """Log ``text`` (cut to :data:`~drd_planner.ros.guard.MAX_ERROR_CHARS`), keep it, put it on ``/diagnostics``.

        ``topic`` names the status (:func:`~drd_planner.ros.status.status_name`): ``plan`` for requests,
        ``maps`` for map messages, ``node`` for configuration, lifecycle and internal errors.
        """
        text = shorten(text)
        self.get_logger().error(text)
        with self._lock:
            self._errors = [*self._errors[-99:], text]
        self._out.status(topic, ok=False, message=text, values={})


def main(args: list[str] | None = None) -> int:
    """Run the lifecycle node until SIGINT / SIGTERM (``autostart:=true`` configures and activates it).

    The ``planner_node`` console script (:mod:`drd_planner.ros.planner_node`) installs the signal
    handlers and parses ``--help`` before it imports this module. Without ``autostart`` the node waits
    for the lifecycle services (``ros2 lifecycle set``). One executor thread takes maps and requests
    while the node's planning thread plans. Returns the exit status: 0, or 2 when the parameters given
    on the command line are refused.
    """
    rclpy.init(args=args)
    try:
        node = PlannerNode()
    except (ParameterException, ValueError, TypeError) as exc:  # an override outside its range or type
        print(f"planner_node: error: {shorten(str(exc))}", file=sys.stderr)
        try_shutdown()
        return 2
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    try:
        if bool(node.get_parameter("autostart").value):
            if node.trigger_configure() == TransitionCallbackReturn.SUCCESS:
                node.trigger_activate()
            else:
                node.get_logger().error("autostart: configure failed; the node waits unconfigured")
        context = node.context
        while context.ok():  # short waits: a signal that only Python saw still ends the loop soon
            executor.spin_once(timeout_sec=SPIN_TIMEOUT_S)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        executor.shutdown()
        node.destroy_node()
        try_shutdown()
    return 0
