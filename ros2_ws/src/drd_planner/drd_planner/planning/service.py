"""The planner service: maps, requests, coalescing, publishing decisions and replanning, without ROS.

:class:`PlannerService` is what the ``drd_planner`` node (:mod:`drd_planner.ros.node`) does apart from ROS
I/O: it holds the loaded priors (:class:`~drd_planner.planning.session.QuerySession`), the maps (one
:class:`~drd_planner.planning.map_store.MapStore`), the robot's latest state, the pending requests and the
published plan. What it sends out goes through a :class:`ServiceOutputs` (the node publishes it; a test can
record it).

Consistency. Maps and requests arrive from the caller's threads; topic requests are planned in
:meth:`PlannerService.serve` (the node's planning thread), service calls in :meth:`PlannerService.plan_now`,
one plan at a time. A plan runs to its end on the map snapshot it started from; a map that arrives meanwhile
makes a new snapshot (its FCL scene and checkers built by :meth:`PlannerService.take_map`) that the next plan
uses. Topic requests are *coalesced*: while a plan runs, a newer request for the same prior supersedes an
older one that has not started (the summary's ``coalesced`` value counts them). Every map that arrives
before a plan is published, or after, is compared with the map that plan was verified on; only the plan's
edges the update can affect are re-checked (:mod:`drd_planner.planning.replan`): the plan is kept if they
stay free, replanned from the robot's state now if one is blocked, and withdrawn if no free path is found.
No plan is published unless every one of its edges was checked free on the snapshot it was planned on;
a plan that breaks that invariant (:class:`~drd_planner.exceptions.InvariantError`) is a bug: reported
with its traceback (:meth:`ServiceOutputs.bug`), never as a refused request, and nothing is published.
"""

from __future__ import annotations

import dataclasses
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from drd_msgs_py.exceptions import MessageError
from drd_msgs_py.topics import topic_base
from drd_planner.arrays import FloatArray
from drd_planner.core.status import PlanStatus
from drd_planner.domains.online import RobotStateTopic
from drd_planner.domains.pose_states import state_from_pose
from drd_planner.exceptions import DrdError, InvariantError, PlanningError
from drd_planner.geometry.map_limits import MapLimits
from drd_planner.planner.endpoints import Endpoint
from drd_planner.planning.cancel import Cancel
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.map_store import MapStore, robot_loader_of, terrain_fit_of
from drd_planner.planning.plan_outcome import PlanOutcome, RefusedPart
from drd_planner.planning.prior_site import prior_sites
from drd_planner.planning.replan import recheck_plan
from drd_planner.planning.requests import (
    DEFAULT_TOLERANCES,
    Goal,
    GoalTolerances,
    goal_endpoint,
    pick_session,
    read_robot_state,
)
from drd_planner.planning.service_outputs import PlanRecord, Published, ServiceOutputs
from drd_planner.planning.session import QuerySession

__all__ = [
    "HISTORY_LENGTH",
    "SNAPSHOTS_KEPT",
    "LiveSettings",
    "PlanRecord",
    "PlannerService",
    "Published",
    "ServiceOutputs",
]

#: Characters of a refused map's reason a plan summary quotes.
MAX_REFUSAL_TEXT = 300
#: Served requests kept in :attr:`PlannerService.history`.
HISTORY_LENGTH = 16
#: The newest records of the history that keep their map snapshot (older ones drop it: a snapshot
#: holds its terrain heightfield, up to 2 MB at the default ``max_terrain_cells``, and obstacle parts;
#: FCL scenes live in the snapshots' own bounded scene cache). 8 covers the bundled bags' plans.
SNAPSHOTS_KEPT = 8


@dataclass(frozen=True)
class LiveSettings:
    """Settings read when they are used (node parameters that may change at run time).

    Attributes:
        seed: the policy seed of each plan.
        replan_on_map_update: replan when a map update blocks the published plan (else withdraw it).
        prior_start: plan from the prior's stored start while no robot state is known.
        state_topics: the robot-state topics (helicopter odometry, arm joint states), for error texts.
    """

    seed: int = 0
    replan_on_map_update: bool = True
    prior_start: bool = False
    state_topics: tuple[str, str] = ("odom", "joint_states")


@dataclass(frozen=True)
class _Request:
    """A goal waiting to be planned: the prior that serves it, the goal, where it came from."""

    session: QuerySession
    goal: Goal
    source: str
    stamp: str
    coalesced: int = 0
    received: float = 0.0  # time.perf_counter() when the request was taken


class PlannerService:
    """See the module docstring.

    Args:
        sessions: the loaded priors (one per domain; :func:`~drd_planner.planning.requests.ambiguity`).
        outputs: where results and reports go.
        frame_id: the planning frame.
        limits: size limits of map messages.
        tolerances: how near a goal must be to a vertex to be that vertex (position, joints, yaw).
        live: the settings read at each use.
        wake: called when there is work for :meth:`serve` (the node wakes its planning thread).
    """

    def __init__(
        self,
        sessions: Sequence[QuerySession],
        outputs: ServiceOutputs,
        *,
        frame_id: str,
        limits: MapLimits = MapLimits.DEFAULT,
        tolerances: GoalTolerances = DEFAULT_TOLERANCES,
        live: Callable[[], LiveSettings] = LiveSettings,
        wake: Callable[[], None] = lambda: None,
    ) -> None:
        self._sessions = tuple(sessions)
        self._out = outputs
        self.frame_id = frame_id
        self._tolerances = tolerances
        self._refused: tuple[int, str] | None = None  # (current map version then, why) of the last refused map
        self._live = live
        self._wake = wake
        margin = self._sessions[0].margin if self._sessions else 0.0
        sites, notes = prior_sites([(s.prior, s.domain) for s in self._sessions])
        for note in notes:
            outputs.warning(note)
        self.maps = MapStore(
            frame_id=frame_id,
            margin=margin,
            limits=limits,
            robot_loader=robot_loader_of(self._sessions, limits),
            terrain_fit=terrain_fit_of([s.domain for s in self._sessions], sites),
        )
        self._snapshot = self.maps.snapshot
        self._robot_states: dict[RobotStateTopic, FloatArray] = {}  # its topic -> the latest robot state
        self._lock = threading.Lock()  # the pending requests
        self._planning = threading.Lock()  # one plan at a time: the sessions' caches, the published plan
        self._pending: dict[str, _Request] = {}
        self._published: Published | None = None
        self._history: deque[PlanRecord] = deque(maxlen=HISTORY_LENGTH)

    # ------------------------------------------------------------------------------------------------
    # Introspection

    @property
    def sessions(self) -> tuple[QuerySession, ...]:
        """The loaded priors."""
        return self._sessions

    @property
    def planning_lock(self) -> threading.Lock:
        """Held by every plan and re-check (one at a time: the priors' caches); hold it to check."""
        return self._planning

    @property
    def snapshot(self) -> MapSnapshot:
        """The current maps (the latest accepted map, once its scene and checkers are prepared)."""
        return self._snapshot

    @property
    def published(self) -> Published | None:
        """The plan out there now (None: none, or it was withdrawn)."""
        return self._published

    @property
    def pending(self) -> int:
        """Requests waiting to be planned."""
        with self._lock:
            return len(self._pending)

    @property
    def history(self) -> tuple[PlanRecord, ...]:
        """The last served requests (at most :data:`HISTORY_LENGTH`), oldest first."""
        return tuple(self._history)

    @property
    def robot_states(self) -> dict[RobotStateTopic, FloatArray]:
        """The robot's latest accepted state per robot-state topic (``odom``, ``joint_states``)."""
        return dict(self._robot_states)

    @property
    def joint_goal_session(self) -> QuerySession | None:
        """The prior that plans joint-space goals (an arm's: MoveIt's requests go to it), if one is loaded."""
        return next((s for s in self._sessions if s.domain.plans_joint_goals), None)

    # ------------------------------------------------------------------------------------------------
    # Maps and robot state

    def take_map(
        self, topic: str, msg: Any, on_accept: Callable[[MapSnapshot], None] | None = None
    ) -> MapSnapshot | None:
        """Apply a map message (:meth:`MapStore.apply`) and make its snapshot current; None if ignored.

        The new snapshot's scene and each prior's checker are built first, so a request served meanwhile
        plans on the previous snapshot and one served after starts checking at once; then ``on_accept``
        is called (the node logs the new version there, before anything is re-checked against it) and the
        planning side is woken (a plan made on an older snapshot right now is published after this and
        must be re-checked against this map as well).

        Raises:
            MessageError, DrdError: the message is refused; the maps are unchanged.
        """
        try:
            snapshot = self.maps.apply(topic, msg)
        except (MessageError, DrdError) as exc:
            # A plan on the maps that are still current says that a newer map was refused, and why.
            self._refused = (self._snapshot.version, f"{topic_base(topic)} refused: {exc}"[:MAX_REFUSAL_TEXT])
            raise
        if snapshot is None:
            return None
        self._prepare(snapshot)
        if on_accept is not None:
            on_accept(snapshot)
        self._snapshot = snapshot
        self._wake()
        return snapshot

    def _prepare(self, snapshot: MapSnapshot) -> None:
        """Build the scene and checkers of ``snapshot`` now; a failure is only logged (the plan meets it again)."""
        for session in self._sessions:
            try:
                session.prepare(snapshot)
            except Exception as exc:  # the plan on this snapshot meets it again
                self._out.warning(f"{session.name}: map version {snapshot.version} not prepared: {exc}")

    def take_robot_state(self, topic: str, msg: Any) -> bool:
        """Keep the robot state of an ``odom`` or ``joint_states`` message; False when it is not ours.

        Raises:
            MessageError, DrdError: the message is refused; the state is unchanged.
        """
        read = read_robot_state(topic, msg, self._sessions, self.frame_id)
        if read is None:
            return False
        self._robot_states[read[0]] = read[1]
        return True

    # ------------------------------------------------------------------------------------------------
    # Requests

    def enqueue(self, goal: Goal, source: str, stamp: str) -> bool:
        """Queue a topic request for :meth:`serve` (superseding an unserved one of the same prior).

        Returns False (and reports why) when no loaded prior serves ``goal``.
        """
        session = pick_session(self._sessions, goal)
        if session is None:
            self._out.error(f"{source} refused: no loaded prior plans for {goal.describe()}")
            return False
        with self._lock:
            older = self._pending.get(session.name)
            coalesced = older.coalesced + 1 if older is not None else 0
            self._pending[session.name] = _Request(
                session, goal, source, stamp, coalesced, received=time.perf_counter()
            )
        self._wake()
        return True

    def serve(self) -> None:
        """Plan the newest pending request of each prior, then re-check the published plan if maps changed."""
        with self._planning:
            with self._lock:
                pending, self._pending = list(self._pending.values()), {}
            for request in pending:
                self._plan_and_publish(
                    request.session,
                    request.goal,
                    None,
                    {
                        "request": request.source,
                        "request_stamp": request.stamp,
                        "coalesced": request.coalesced,
                    },
                    wait_s=time.perf_counter() - request.received,
                )
            published = self._published
            if published is not None and published.snapshot is not self._snapshot:
                try:
                    self._recheck(published)  # every map that arrived before the plan was published, or since
                except Exception:
                    self._withdraw(published.session, self._snapshot, why="its re-check failed")
                    raise

    def plan_now(self, goal: Goal, start: Goal | None, source: str = "get_plan") -> Any | None:
        """:meth:`serve_request`'s plan as :meth:`ServiceOutputs.plan` gave it, or None (the reason reported)."""
        return self.serve_request(goal, start, source).sent

    def serve_request(
        self, goal: Goal, start: Goal | None, source: str = "get_plan", *, cancel: Cancel = None
    ) -> PlanOutcome:
        """Serve one request now (a service call or action goal) and say what it came to.

        ``start``: a pose start (helicopter) or joint angles (arm); None: the robot's state. ``cancel`` stops
        the plan between two checks (:class:`~drd_planner.planning.cancel.PlanCancelled` is raised; nothing is
        published).
        """
        session = pick_session(self._sessions, goal)
        if session is None:
            return self._refuse(f"{source} refused: no loaded prior plans for {goal.describe()}", "prior")
        start_state = None
        joints = session.domain.plans_joint_goals
        if start is not None and joints and start.joints is not None:
            start_state = start.joints  # joint angles given with the request (MoveIt's start state)
        elif start is not None:
            if joints or start.yaw is None:
                topic = session.domain.robot_state_topic
                joint_start = f"a start of {session.name} (joint angles) comes from {topic}, not a pose"
                why = joint_start if joints else "a start pose needs its orientation (the vehicle's yaw)"
                return self._refuse(f"{source} refused: {why}", "start")
            assert start.position is not None
            start_state = state_from_pose(start.position, start.yaw)
        received = time.perf_counter()
        with self._planning:
            values, wait_s = {"request": source}, time.perf_counter() - received
            outcome = self._plan_and_publish(session, goal, start_state, values, wait_s=wait_s, cancel=cancel)
        self._wake()  # re-check it if a map arrived while it was planned
        return outcome

    def _refuse(self, text: str, part: RefusedPart) -> PlanOutcome:
        """Report a request refused before planning (``part``: what it is about)."""
        self._out.error(text)
        return PlanOutcome(refusal=text, refused=part)

    def replan(self) -> tuple[Any | None, bool]:
        """Plan again to the published plan's goal from the robot's state now.

        Returns the new published plan (None: none) and whether there was a published plan at all.
        """
        published = self._published
        if published is None:
            return None, False
        with self._planning:
            outcome = self._plan_and_publish(published.session, published.goal, None, {"request": "replan"})
        self._wake()
        return outcome.sent, True

    # ------------------------------------------------------------------------------------------------
    # Planning and publishing

    def _start_for(self, session: QuerySession) -> Endpoint:
        """Where a plan of ``session`` starts when the request gives no start: the robot's state."""
        kind = session.domain.robot_state_topic
        state = self._robot_states.get(kind)
        if state is not None:
            return state
        live = self._live()
        if live.prior_start:
            return int(session.domain.start)
        topic = live.state_topics[1] if kind == "joint_states" else live.state_topics[0]
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
        cancel: Cancel = None,
    ) -> PlanOutcome:
        """Plan on the current snapshot and send the result out; ``wait_s``: how long the request waited."""
        snapshot = self._snapshot
        part: RefusedPart = "start"
        try:
            begin = start if start is not None else self._start_for(session)
            part = "goal"
            end = goal_endpoint(session, goal, snapshot, self._tolerances)
            part = "maps"
            result = session.plan(snapshot, begin, end, seed=self._live().seed, cancel=cancel)
        except DrdError as exc:
            return self._refuse(f"{values.get('request', 'request')} refused: {exc}", part)
        except InvariantError as exc:  # a bug, not a refusal: reported with its traceback, nothing published
            text = f"{values.get('request', 'request')}: internal error, nothing published: {type(exc).__name__}: {exc}"
            self._out.bug(text, exc)
            return PlanOutcome(internal_error=text, session=session, snapshot=snapshot)
        # A start or goal the prior cannot serve is a refused request, not a plan.
        if result.status is PlanStatus.REFUSED:
            self._out.error(f"{values.get('request', 'request')} refused: {result.message}")
            return PlanOutcome(result=result, session=session, snapshot=snapshot)
        refused = self._refused
        if refused is not None and refused[0] >= snapshot.version:
            values = {**values, "newer_map_refused": refused[1]}
        record = PlanRecord(session, result, snapshot, dict(values))
        self._remember(record)

        def publish(stamp: tuple[int, int]) -> Any | None:
            if not result.ok:
                return None
            path, out_there = self._out.plan(session, result, snapshot, stamp)
            if out_there:  # an inactive node publishes nothing, so it has no plan out there
                self._published = Published(session, result, snapshot, goal)
            return path

        sent = self._out.result(record, wait_s=wait_s, publish=publish)
        return PlanOutcome(sent, result, session=session, snapshot=snapshot)

    def _remember(self, record: PlanRecord) -> None:
        """Add ``record`` to the history; the record :data:`SNAPSHOTS_KEPT` back lets go of its snapshot."""
        self._history.append(record)
        if len(self._history) > SNAPSHOTS_KEPT:
            old = self._history[-SNAPSHOTS_KEPT - 1]
            if old.snapshot is not None:
                self._history[-SNAPSHOTS_KEPT - 1] = dataclasses.replace(old, snapshot=None)

    # ------------------------------------------------------------------------------------------------
    # Map updates after a published plan

    def _recheck(self, published: Published) -> None:
        snapshot = self._snapshot
        session = published.session
        try:
            outcome = recheck_plan(session, published.result.path_edges, published.snapshot, snapshot)
        except DrdError as exc:
            reason = f"re-check after map update failed: {exc}"
            self._out.error(f"{reason}; replanning")
        else:
            if outcome.kept:
                self._published = Published(session, published.result, snapshot, published.goal)
                self._out.kept(session, outcome, snapshot)
                return
            reason = outcome.reason
            self._out.warning(reason)
        if not self._live().replan_on_map_update:
            self._withdraw(session, snapshot, why=f"{reason}; replan_on_map_update is false")
        elif (
            self._plan_and_publish(
                session, published.goal, None, {"request": "map_update", "replan_reason": reason}
            ).sent
            is None
        ):
            self._withdraw(session, snapshot, why="no replacement was found")

    def _withdraw(self, session: QuerySession, snapshot: MapSnapshot, *, why: str) -> None:
        """Take the published plan back: it is no longer known free on the current maps."""
        if self._published is None:
            return
        self._published = None
        self._out.withdraw(session)
        self._out.error(
            f"{session.name}: the published plan is blocked on map version {snapshot.version} ({why}); "
            "published an empty plan"
        )
