"""Plan a bag's request offline as the node does (no ROS): its maps, the robot's state, its goal.

The node plans a request on the maps it has received, from the robot's latest accepted state
(``odom`` for the helicopter, ``joint_states`` for the arm), to the goal as
:func:`~drd_planner.planning.requests.goal_endpoint` reads it. :func:`plan_bag_request` does the same
from a bag's decoded messages, with the node's own readers, so that ``drd plan --bag``, the bag
generator's self-check and the replay tests agree with the node by construction.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from drd_msgs_py.bags import BagMaps, BagMessage, BagRequest, maps_at_request, topic_base
from drd_msgs_py.exceptions import MessageError
from drd_planner.arrays import FloatArray
from drd_planner.exceptions import PlanningError
from drd_planner.planner.endpoints import Endpoint
from drd_planner.planning.query_session import QueryPlanResult, QuerySession
from drd_planner.planning.requests import (
    Goal,
    goal_endpoint,
    goal_from_pose,
    joint_vector,
    start_from_odometry,
)

#: The node's defaults of ``goal_tolerance`` (m) and ``joint_tolerance`` (rad).
GOAL_TOLERANCE_M = 1.0
JOINT_TOLERANCE_RAD = 0.05

__all__ = ["BagPlan", "plan_bag_request", "request_goal", "robot_state_at"]


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
    result: QueryPlanResult
    notes: tuple[str, ...] = ()


def request_goal(session: QuerySession, request: BagRequest, frame: str) -> Goal:
    """The :class:`Goal` of a ``goal_pose`` or ``goal_joints`` request, read as the node reads it.

    Raises:
        MessageError: a pose in another frame or not finite, or joints the prior does not plan for.
    """
    if request.kind == "goal_joints":
        if not session.is_arm:
            raise MessageError("goal_joints needs an arm prior")
        return Goal(joints=joint_vector(request.message, session.joint_names, "goal_joints"))
    return goal_from_pose(request.message, frame, "goal_pose")


def robot_state_at(
    session: QuerySession, messages: Sequence[BagMessage], time_ns: int, frame: str
) -> tuple[FloatArray | None, tuple[str, ...]]:
    """The robot's last accepted state at or before ``time_ns``, and why any later-refused ones were dropped.

    The helicopter's comes from ``odom`` (x, y, z m; yaw rad), the arm's from ``joint_states`` (rad).
    """
    topic = "joint_states" if session.is_arm else "odom"
    state: FloatArray | None = None
    notes: list[str] = []
    for m in messages:
        if m.time_ns > time_ns:
            break
        if topic_base(m.topic) != topic:
            continue
        try:
            if session.is_arm:
                state = joint_vector(m.message, session.joint_names, "joint_states")
            else:
                state = start_from_odometry(m.message, frame)
        except MessageError as exc:
            notes.append(f"{m.topic} refused: {exc}")
    return state, tuple(notes)


def plan_bag_request(
    session: QuerySession,
    messages: Sequence[BagMessage],
    index: int,
    *,
    frame: str,
    seed: int = 0,
    goal_tolerance: float = GOAL_TOLERANCE_M,
    joint_tolerance: float = JOINT_TOLERANCE_RAD,
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
        messages, index, frame_id=frame, margin=session.margin, robot_from_description=session.robot_loader
    )
    goal = request_goal(session, request, frame)
    state, notes = robot_state_at(session, messages[: request.position], request.time_ns, frame)
    start: Endpoint
    if state is not None:
        start = state
    elif prior_start:
        start = int(session.domain.start)
    else:
        topic = "joint_states" if session.is_arm else "odom"
        raise PlanningError(
            f"request {index}: the bag has no accepted {topic} message before it (no robot state to plan "
            "from; plan from the prior's start with --prior-start)"
        )
    end = goal_endpoint(
        session, goal, maps.snapshot, tolerance=goal_tolerance, joint_tolerance=joint_tolerance
    )
    result = session.plan(maps.snapshot, start, end, seed=seed)
    return BagPlan(request, maps, start, end, result, notes)
