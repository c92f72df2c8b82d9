"""Plan a bag's request offline as the node does (no ROS): its maps, the robot's state, its goal.

The node plans a request on the maps it has received, from the robot's latest accepted state
(``odom`` for the helicopter, ``joint_states`` for the arm), to the goal as
:func:`~drd_planner.planning.requests.goal_endpoint` reads it. :func:`plan_bag_request` does the same
from a bag's decoded messages, with the node's own readers, so that ``drd plan --bag``, the bag
generator's self-check and the replay tests agree with the node by construction.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from drd_msgs_py.bags import BagMessage, BagRequest, request_at, topic_base
from drd_msgs_py.exceptions import MessageError
from drd_msgs_py.obstacles import Obstacle
from drd_planner.arrays import FloatArray
from drd_planner.exceptions import DrdError, PlanningError
from drd_planner.planner.endpoints import Endpoint
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.map_store import MAP_SOURCES, MapStore, RobotLoader, TerrainFit, terrain_fit_of
from drd_planner.planning.prior_site import prior_sites
from drd_planner.planning.requests import (
    DEFAULT_TOLERANCES,
    Goal,
    GoalTolerances,
    goal_endpoint,
    read_goal,
    read_robot_state,
)
from drd_planner.planning.session import QuerySession
from drd_planner.planning.session_plan import SessionPlan

__all__ = [
    "BagMaps",
    "BagPlan",
    "maps_at_request",
    "maps_until",
    "plan_bag_request",
    "request_goal",
    "robot_state_at",
]


@dataclass(frozen=True)
class BagMaps:
    """The maps in force at some point of a bag.

    Attributes:
        snapshot: the planner's map snapshot (version = accepted map messages that changed it).
        robot_description: the latest ``robot_description`` text (None: none in the bag so far).
        refused: one line per map message the planner would refuse (and ignore).
        applied: how many map messages were accepted.
        obstacles: the named obstacles behind ``snapshot.obstacles`` (key ``ns/id``), as their markers gave them.
    """

    snapshot: MapSnapshot
    robot_description: str | None = None
    refused: tuple[str, ...] = ()
    applied: int = 0
    obstacles: dict[str, Obstacle] = field(default_factory=dict)


def _apply_maps(
    messages: Sequence[BagMessage],
    *,
    frame_id: str,
    margin: float,
    robot_loader: RobotLoader | None,
    terrain_fit: TerrainFit | None,
) -> BagMaps:
    """The maps after the map messages of ``messages``, applied by a :class:`MapStore` as the node does."""
    store = MapStore(frame_id=frame_id, margin=margin, robot_loader=robot_loader, terrain_fit=terrain_fit)
    refused: list[str] = []
    applied = 0
    for m in messages:
        base = topic_base(m.topic)
        if base not in MAP_SOURCES:
            continue
        try:
            store.apply(base, m.message)
        except (MessageError, DrdError) as exc:
            refused.append(f"{base} at {m.time_ns} ns refused: {exc}")
            continue
        applied += 1
    return BagMaps(store.snapshot, store.robot_description, tuple(refused), applied, dict(store.obstacles))


def maps_until(
    messages: Sequence[BagMessage],
    time_ns: int,
    *,
    frame_id: str,
    margin: float,
    robot_loader: RobotLoader | None = None,
    terrain_fit: TerrainFit | None = None,
) -> BagMaps:
    """The maps after every map message at or before ``time_ns`` (time-ordered ``messages``).

    Args:
        messages: the bag's decoded messages in time order (:func:`drd_msgs_py.bags.read_bag`).
        time_ns: bag time, inclusive.
        frame_id: the planning frame (maps in another frame are refused, as by the node).
        margin: collision margin of the snapshot (metres; the session's ``margin``).
        robot_loader: turns a ``robot_description`` URDF into the snapshot's robot (a session's
            ``robot_loader``); None keeps only the text.
        terrain_fit: refuses a terrain that cannot be the prior's
        (:func:`~drd_planner.planning.map_store.terrain_fit_of`).
    """
    upto = [m for m in messages if m.time_ns <= time_ns]
    return _apply_maps(upto, frame_id=frame_id, margin=margin, robot_loader=robot_loader, terrain_fit=terrain_fit)


def maps_at_request(
    messages: Sequence[BagMessage],
    index: int,
    *,
    frame_id: str,
    margin: float,
    robot_loader: RobotLoader | None = None,
    terrain_fit: TerrainFit | None = None,
) -> tuple[BagMaps, BagRequest]:
    """The maps in force when the ``index``-th (0-based) request arrives, and that request.

    Every map message before the request in bag order counts (arguments as :func:`maps_until`).

    Raises:
        BagError: the bag has no request ``index`` (the text says how many it has).
    """
    request = request_at(messages, index)
    maps = _apply_maps(
        messages[: request.position],
        frame_id=frame_id,
        margin=margin,
        robot_loader=robot_loader,
        terrain_fit=terrain_fit,
    )
    return maps, request


@dataclass(frozen=True)
class BagPlan:
    """One request of a bag, planned.

    Attributes:
        request: the request (its index, time and message).
        maps: the maps in force when it arrived (with any map message that was refused).
        start: (D,) the robot's state it was planned from, or the prior's start vertex id.
        goal: the goal as the planner took it (a vertex id, or a (D,) state).
        result: the plan.
        notes: robot-state messages that were refused (the node drops them and keeps the last good one).
    """

    request: BagRequest
    maps: BagMaps
    start: Endpoint
    goal: Endpoint
    result: SessionPlan
    notes: tuple[str, ...] = ()


def request_goal(session: QuerySession, request: BagRequest, frame: str) -> Goal:
    """The :class:`Goal` of a ``goal_pose`` or ``goal_joints`` request, read as the node reads it.

    Raises:
        MessageError: a pose in another frame or not finite, or joints the prior does not plan for.
        PlanningError: ``goal_joints`` without an arm prior.
    """
    return read_goal(request.kind, request.message, [session], frame)


def robot_state_at(
    session: QuerySession, messages: Sequence[BagMessage], time_ns: int, frame: str
) -> tuple[FloatArray | None, tuple[str, ...]]:
    """The robot's last accepted state at or before ``time_ns``, and why any later-refused ones were dropped.

    The helicopter's comes from ``odom`` (x, y, z m; yaw rad), the arm's from ``joint_states`` (rad).
    """
    topic = session.domain.robot_state_topic
    state: FloatArray | None = None
    notes: list[str] = []
    for m in messages:
        if m.time_ns > time_ns:
            break
        if topic_base(m.topic) != topic:
            continue
        try:
            read = read_robot_state(topic, m.message, [session], frame)
        except MessageError as exc:
            notes.append(f"{m.topic} refused: {exc}")
            continue
        if read is not None:
            state = read[1]
    return state, tuple(notes)


def plan_bag_request(
    session: QuerySession,
    messages: Sequence[BagMessage],
    index: int,
    *,
    frame: str,
    seed: int = 0,
    tolerances: GoalTolerances = DEFAULT_TOLERANCES,
    prior_start: bool = False,
) -> BagPlan:
    """Plan the ``index``-th request of time-ordered ``messages`` as the node would.

    ``prior_start`` plans from the prior's stored start when the bag has no robot state before the
    request (the node's ``start_without_robot_state: prior_start``); otherwise that is an error.

    Raises:
        MessageError: the request, or the maps, cannot be read (BagError: no such request).
        PlanningError: no robot state before the request, or no maps yet.
    """
    maps, request = maps_at_request(
        messages,
        index,
        frame_id=frame,
        margin=session.margin,
        robot_loader=session.robot_loader,
        terrain_fit=terrain_fit_of([session.domain], prior_sites([(session.prior, session.domain)])[0]),
    )
    goal = request_goal(session, request, frame)
    state, notes = robot_state_at(session, messages[: request.position], request.time_ns, frame)
    start: Endpoint
    if state is not None:
        start = state
    elif prior_start:
        start = int(session.domain.start)
    else:
        topic = session.domain.robot_state_topic
        raise PlanningError(
            f"request {index}: the bag has no accepted {topic} message before it (no robot state to plan "
            "from; plan from the prior's start with --prior-start)"
        )
    end = goal_endpoint(session, goal, maps.snapshot, tolerances)
    result = session.plan(maps.snapshot, start, end, seed=seed)
    return BagPlan(request, maps, start, end, result, notes)
