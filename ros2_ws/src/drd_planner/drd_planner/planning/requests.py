"""Requests and robot states as the node reads them: goals, starts, and which prior serves them.

A goal is a :class:`Goal`: a position (and yaw) from ``goal_pose`` / ``get_plan``, or joint angles
from ``goal_joints``. :func:`goal_endpoint` turns it into what the planner takes for one session:

- a goal within ``goal_tolerance`` (m) of the prior's stored goal (``joint_tolerance`` rad for joints)
  is that vertex, so a tree built for the stored query serves it;
- else, within the tolerance of another vertex, the nearest such vertex;
- else the goal state itself (x, y, z, yaw; or the joint angles), joined to the graph by new, checked
  motions. An arm's end-effector position goal must lie within ``goal_tolerance`` of a roadmap vertex's
  end effector (there is no inverse kinematics).

**A helicopter goal's yaw is honoured**: a vertex serves a pose goal only when its heading is within
``goal_yaw_tolerance`` (rad) of the goal's yaw; otherwise the goal is its own state and the path ends with
exactly that heading. A goal whose orientation is the zero quaternion (all four components 0, "no
orientation") has no yaw: any vertex at its position serves it, and otherwise the path may arrive at it with
any heading (:class:`~drd_planner.planner.dubins_connector.DubinsConnector`).

The robot's state comes from ``odom`` (``nav_msgs/Odometry``, helicopter: x, y, z, yaw) or
``joint_states`` (``sensor_msgs/JointState``, arm); :func:`pick_session` says which loaded prior
serves a request: the one of the request's domain (a pose: the helicopter's, else the arm's end
effector; joints: the arm's). Two priors of one domain are ambiguous and refused at configure
(:func:`ambiguity`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from drd_msgs_py.exceptions import MessageError
from drd_msgs_py.obstacles import pose_from_msg
from drd_msgs_py.topics import topic_base
from drd_planner.arrays import FloatArray
from drd_planner.domains.online import RobotStateTopic
from drd_planner.domains.pose_states import state_from_pose, yaw_from_quaternion
from drd_planner.exceptions import PlanningError
from drd_planner.planner.endpoints import Endpoint
from drd_planner.planning.map_intake import pose_of
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.session import QuerySession

__all__ = [
    "DEFAULT_TOLERANCES",
    "Goal",
    "GoalTolerances",
    "ambiguity",
    "goal_endpoint",
    "goal_from_pose",
    "joint_vector",
    "pick_session",
    "read_goal",
    "read_robot_state",
    "start_from_odometry",
]


@dataclass(frozen=True)
class Goal:
    """A requested goal.

    Attributes:
        position: (3,) metres in the planning frame (a pose goal), or None.
        yaw: the pose goal's heading (rad); None: any heading (a pose without orientation); 0 for joint goals.
        joints: (D,) joint angles (rad) in the session's joint order (a joint goal), or None.
    """

    position: FloatArray | None = None
    yaw: float | None = 0.0
    joints: FloatArray | None = None

    def describe(self) -> str:
        """The goal in one short phrase for logs."""
        if self.joints is not None:
            return f"joints {np.round(self.joints, 3).tolist()}"
        assert self.position is not None
        heading = "any yaw" if self.yaw is None else f"yaw {self.yaw:.2f}"
        return f"position {np.round(self.position, 2).tolist()} {heading}"


@dataclass(frozen=True)
class GoalTolerances:
    """How near a requested goal must be to a graph vertex to be that vertex.

    Attributes:
        position_m: metres per axis (a pose goal; an arm's end-effector goal).
        joint_rad: radians per joint (a joint goal).
        yaw_rad: radians between a pose goal's yaw and the vertex's heading (the helicopter).
    """

    position_m: float = 1.0
    joint_rad: float = 0.05
    yaw_rad: float = 0.1


#: The node's default goal tolerances (its parameters' defaults).
DEFAULT_TOLERANCES = GoalTolerances()


def goal_from_pose(msg: Any, frame: str, what: str = "goal") -> Goal:
    """The :class:`Goal` of a ``PoseStamped`` in ``frame``; a wrong frame, NaN or a bad quaternion is refused.

    The zero quaternion (all four components exactly 0) means "no orientation": a goal with any yaw.
    """
    got = str(msg.header.frame_id)
    if got != frame:
        raise MessageError(f"{what} is in frame {got[:80]!r}; the planner works in {frame!r}")
    q = msg.pose.orientation
    if (q.x, q.y, q.z, q.w) == (0.0, 0.0, 0.0, 0.0):
        p = msg.pose.position
        position = np.array([p.x, p.y, p.z], dtype=np.float64)
        if not np.all(np.isfinite(position)):
            raise MessageError(f"{what} position must be finite, got {position.tolist()}")
        return Goal(position=position, yaw=None)
    pose = pose_of(pose_from_msg(msg.pose, what))
    return Goal(position=np.array(pose.position, dtype=np.float64), yaw=yaw_from_quaternion(pose.quaternion_xyzw))


def start_from_odometry(msg: Any, frame: str) -> FloatArray:
    """(4,) helicopter state (x, y, z m, yaw rad) of a ``nav_msgs/Odometry`` whose pose is in ``frame``."""
    got = str(msg.header.frame_id)
    if got != frame:
        raise MessageError(f"odometry is in frame {got[:80]!r}; the planner works in {frame!r}")
    pose = pose_of(pose_from_msg(msg.pose.pose, "odometry pose"))
    return state_from_pose(pose.position, yaw_from_quaternion(pose.quaternion_xyzw))


def joint_vector(msg: Any, joint_names: Sequence[str], what: str = "joint state") -> FloatArray:
    """(D,) angles (rad) of a ``JointState`` in the order of ``joint_names``; other joints are ignored."""
    names = [str(n) for n in msg.name]
    positions = np.asarray(msg.position, dtype=np.float64).ravel()
    if len(names) != positions.size:
        raise MessageError(f"{what}: {len(names)} joint names but {positions.size} positions")
    if len(set(names)) != len(names):
        raise MessageError(f"{what}: joint names repeat")
    missing = [j for j in joint_names if j not in names]
    if missing:
        raise MessageError(f"{what}: missing joints {missing}; the prior plans for {list(joint_names)}")
    q = np.array([positions[names.index(j)] for j in joint_names])
    if not np.all(np.isfinite(q)):
        raise MessageError(f"{what}: joint positions must be finite")
    return q


def _joint_session(sessions: Sequence[QuerySession]) -> QuerySession | None:
    """The prior that plans joint-space goals (an arm's), or None."""
    return next((s for s in sessions if s.domain.plans_joint_goals), None)


def read_goal(topic: str, msg: Any, sessions: Sequence[QuerySession], frame: str) -> Goal:
    """The :class:`Goal` of a ``goal_pose`` (PoseStamped) or ``goal_joints`` (JointState) message.

    The one goal parser of the node, the bag tools and ``drd plan --bag``; ``topic`` may carry a namespace.

    Raises:
        MessageError: a pose in another frame or not finite, joints the arm prior does not plan for.
        PlanningError: ``goal_joints`` without a prior that plans joint-space goals (an arm's).
    """
    if topic_base(topic) == "goal_joints":
        joint = _joint_session(sessions)
        if joint is None:
            raise PlanningError("no prior that plans joint-space goals (an arm's) is loaded")
        return Goal(joints=joint_vector(msg, joint.joint_names, "goal_joints"))
    return goal_from_pose(msg, frame, "goal_pose")


def read_robot_state(
    topic: str, msg: Any, sessions: Sequence[QuerySession], frame: str
) -> tuple[RobotStateTopic, FloatArray] | None:
    """(topic, state) of an ``odom`` (a pose: x, y, z m, yaw rad) or ``joint_states`` (joint angles, rad) message.

    None: a ``joint_states`` message while no loaded prior takes its state from ``joint_states`` (a
    helicopter stack's joints are not ours).

    Raises:
        MessageError: a pose in another frame or not finite; joints missing, repeated or not finite.
    """
    if topic_base(topic) == "joint_states":
        joint = next((s for s in sessions if s.domain.robot_state_topic == "joint_states"), None)
        return None if joint is None else ("joint_states", joint_vector(msg, joint.joint_names, "joint_states"))
    return "odom", start_from_odometry(msg, frame)


def ambiguity(sessions: Sequence[QuerySession]) -> str | None:
    """Why ``sessions`` cannot serve requests unambiguously (two priors of one domain), or None."""
    seen: dict[str, str] = {}
    for session in sessions:
        domain = session.domain.name
        if domain in seen:
            return (
                f"priors {seen[domain]!r} and {session.name!r} both plan for the {domain} domain: a request "
                "could go to either; load one prior per domain (run one node per prior, in its own namespace)"
            )
        seen[domain] = session.name
    return None


def pick_session(sessions: Sequence[QuerySession], goal: Goal) -> QuerySession | None:
    """The prior that serves ``goal``: joints go to the one that plans joint-space goals (the arm's).

    A pose goes to a prior whose goals are poses (the helicopter's), else to the joint-space one (the arm's
    end effector).
    """
    joint = _joint_session(sessions)
    if goal.joints is not None:
        return joint
    return next((s for s in sessions if not s.domain.plans_joint_goals), joint)


def goal_endpoint(
    session: QuerySession, goal: Goal, snapshot: MapSnapshot, tolerances: GoalTolerances = DEFAULT_TOLERANCES
) -> Endpoint:
    """What the planner takes for ``goal`` in ``session`` (module docstring): a vertex id or a state."""
    domain = session.domain
    stored = int(domain.goal)
    if goal.joints is not None:
        return _nearest_within(session, goal.joints, stored, tolerances.joint_rad, lambda s: np.abs(s - goal.joints))
    assert goal.position is not None
    if domain.position_goals == "vertex":  # the vertex whose position (an arm's end effector) is nearest
        state = session.goal_state_from_position(goal.position, snapshot=snapshot, tolerance=tolerances.position_m)
        return stored if np.array_equal(state, session.vertex_state(stored)) else state
    return _helicopter_goal(session, goal.position, goal.yaw, stored, tolerances)


def _nearest_within(session: QuerySession, want: FloatArray, stored: int, tolerance: float, gap: Any) -> Endpoint:
    """The stored goal if within ``tolerance`` (max per coordinate), else the nearest vertex within it, or ``want``."""
    states = session.prior.graph.vertex_states
    if states is None:
        return want
    if np.max(gap(states[stored])) <= tolerance:
        return stored
    gaps = np.max(gap(states), axis=1)
    best = int(np.argmin(gaps))
    return best if gaps[best] <= tolerance else np.asarray(want, dtype=np.float64)


def _helicopter_goal(
    session: QuerySession, position: FloatArray, yaw: float | None, stored: int, tolerances: GoalTolerances
) -> Endpoint:
    """The vertex at the goal position whose heading matches its yaw (any, without one), else the goal state."""
    wanted = state_from_pose(position, 0.0 if yaw is None else yaw)
    if yaw is None:
        wanted[3] = np.nan  # any heading: the connector joins it with free arrival headings
    states = session.prior.graph.vertex_states
    if states is None:
        return wanted
    offsets = np.max(np.abs(states[:, :3] - position), axis=1)  # metres, per axis as goal_tolerance says
    near = offsets <= tolerances.position_m
    if yaw is not None and states.shape[1] > 3:
        turn = np.abs(np.mod(states[:, 3] - yaw + np.pi, 2.0 * np.pi) - np.pi)  # rad
        near &= turn <= tolerances.yaw_rad
    else:
        turn = np.zeros(states.shape[0])
    if near[stored]:
        return stored
    candidates = np.flatnonzero(near)
    if candidates.size == 0:
        return wanted
    order = np.lexsort((candidates, turn[candidates], offsets[candidates]))
    return int(candidates[order[0]])
