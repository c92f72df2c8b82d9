"""MoveIt's ``GetMotionPlan`` (``moveit_msgs/srv/GetMotionPlan``) read and answered for the arm prior, ROS-free.

:func:`read_motion_request` reads a ``MotionPlanRequest`` (message objects, or stand-ins with its fields):

- ``start_state.joint_state``: the start's joint angles (rad) by name, every planned joint named; an empty
  joint state means the robot's current state (the latest ``joint_states``), as in MoveIt;
- ``goal_constraints``: the first constraint set with joint constraints naming every planned joint is the goal
  (its ``position`` values, rad); position, orientation and visibility constraints need inverse kinematics,
  which the planner does not have: ``INVALID_GOAL_CONSTRAINTS``;
- ``path_constraints`` and ``trajectory_constraints`` are refused (``INVALID_GOAL_CONSTRAINTS`` /
  ``FAILURE``: the planner's paths obey none); ``group_name``, ``pipeline_id``, ``planner_id`` and
  ``allowed_planning_time`` are taken as they are (the node's own budgets bound a plan);
- ``max_velocity_scaling_factor`` in (0, 1] scales the trajectory's joint speed (0: 1, as MoveIt's default).

:func:`moveit_error` gives MoveIt's error code of what a served request came to (via
:func:`~drd_planner.planning.nav2_codes.nav2_error`'s classification), and :func:`timed_waypoints` the
``time_from_start`` of each waypoint of a found path.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.planning.nav2_codes import nav2_error
from drd_planner.planning.plan_outcome import PlanOutcome
from drd_planner.planning.requests import Goal

__all__ = [
    "JOINT_SPEED_RAD_S",
    "MOVEIT_CODES",
    "MotionRequest",
    "MoveItError",
    "moveit_error",
    "read_motion_request",
    "timed_waypoints",
]

#: The MoveIt error codes the planner answers with (moveit_msgs/msg/MoveItErrorCodes).
MOVEIT_CODES = {
    "SUCCESS": 1,
    "FAILURE": 99999,
    "PLANNING_FAILED": -1,
    "TIMED_OUT": -6,
    "START_STATE_IN_COLLISION": -10,
    "START_STATE_INVALID": -26,
    "GOAL_IN_COLLISION": -12,
    "GOAL_STATE_INVALID": -27,
    "INVALID_GROUP_NAME": -15,
    "INVALID_GOAL_CONSTRAINTS": -16,
    "INVALID_ROBOT_STATE": -17,
}
#: Nav2's classification of an outcome (:func:`nav2_error`) -> MoveIt's code.
_FROM_NAV2 = {
    "NONE": "SUCCESS",
    "INVALID_PLANNER": "INVALID_GROUP_NAME",
    "TF_ERROR": "INVALID_ROBOT_STATE",
    "START_OUTSIDE_MAP": "START_STATE_INVALID",
    "GOAL_OUTSIDE_MAP": "GOAL_STATE_INVALID",
    "START_OCCUPIED": "START_STATE_IN_COLLISION",
    "GOAL_OCCUPIED": "GOAL_IN_COLLISION",
    "TIMEOUT": "TIMED_OUT",
    "NO_VALID_PATH": "PLANNING_FAILED",
    "UNKNOWN": "FAILURE",
}
#: Joint speed (rad/s) of the fastest joint along a trajectory at velocity scaling 1.
JOINT_SPEED_RAD_S = 0.5


@dataclass(frozen=True)
class MoveItError:
    """One MoveIt error: the code's name (a key of :data:`MOVEIT_CODES`) and the text for ``message``."""

    name: str
    text: str

    @property
    def code(self) -> int:
        """The code's number (``MoveItErrorCodes.val``)."""
        return MOVEIT_CODES[self.name]


@dataclass(frozen=True)
class MotionRequest:
    """A readable request: the goal (joints), the start (joints; None: the robot's state), the speed scaling."""

    goal: Goal
    start: Goal | None
    velocity_scaling: float


def _joints(names: Sequence[Any], values: Sequence[Any], joint_names: Sequence[str]) -> FloatArray | str:
    """(D,) angles in the order of ``joint_names``, or why not."""
    by_name = {str(n): float(v) for n, v in zip(names, values, strict=False)}
    if len(names) != len(values):
        return f"{len(names)} joint names but {len(values)} positions"
    missing = [j for j in joint_names if j not in by_name]
    if missing:
        return f"missing joints {missing}; the arm plans for {list(joint_names)}"
    q = np.array([by_name[j] for j in joint_names], dtype=np.float64)
    if not np.all(np.isfinite(q)):
        return f"joint positions must be finite, got {q.tolist()}"
    return q


def _goal(constraints: Sequence[Any], joint_names: Sequence[str]) -> FloatArray | MoveItError:
    """The first goal constraint set that is all joints, as angles; else why not."""
    if not constraints:
        return MoveItError("INVALID_GOAL_CONSTRAINTS", "no goal constraints")
    reasons = []
    for k, c in enumerate(constraints):
        others = [
            kind
            for kind in ("position_constraints", "orientation_constraints", "visibility_constraints")
            if len(getattr(c, kind))
        ]
        if others:
            reasons.append(f"set {k} has {', '.join(others)} (no inverse kinematics: give joint constraints)")
            continue
        joints = c.joint_constraints
        q = _joints([j.joint_name for j in joints], [j.position for j in joints], joint_names)
        if isinstance(q, str):
            reasons.append(f"set {k}: {q}")
            continue
        return q
    return MoveItError("INVALID_GOAL_CONSTRAINTS", "; ".join(reasons))


def _empty_constraints(c: Any) -> bool:
    return not any(
        len(getattr(c, kind))
        for kind in (
            "joint_constraints",
            "position_constraints",
            "orientation_constraints",
            "visibility_constraints",
        )
    )


def read_motion_request(request: Any, joint_names: Sequence[str]) -> MotionRequest | MoveItError:
    """The goal, start and speed scaling of a ``MotionPlanRequest``, or the error that refuses it."""
    if not _empty_constraints(request.path_constraints):
        return MoveItError("INVALID_GOAL_CONSTRAINTS", "path constraints are not supported")
    if len(request.trajectory_constraints.constraints):
        return MoveItError("FAILURE", "trajectory constraints are not supported")
    goal = _goal(list(request.goal_constraints), joint_names)
    if isinstance(goal, MoveItError):
        return goal
    state = request.start_state.joint_state
    start: Goal | None = None
    if len(state.name) or len(state.position):
        q = _joints(list(state.name), list(state.position), joint_names)
        if isinstance(q, str):
            return MoveItError("INVALID_ROBOT_STATE", f"start_state: {q}")
        start = Goal(joints=q)
    scaling = float(request.max_velocity_scaling_factor)
    if not np.isfinite(scaling) or scaling < 0.0 or scaling > 1.0:
        return MoveItError("FAILURE", f"max_velocity_scaling_factor must be in [0, 1], got {scaling}")
    return MotionRequest(Goal(joints=goal), start, scaling if scaling > 0.0 else 1.0)


def moveit_error(outcome: PlanOutcome) -> MoveItError:
    """MoveIt's error of a served request (``SUCCESS`` with a verified path); see the module docstring."""
    nav2 = nav2_error(outcome)
    return MoveItError(_FROM_NAV2.get(nav2.name, "FAILURE"), nav2.text)


def timed_waypoints(states: FloatArray, velocity_scaling: float = 1.0) -> FloatArray:
    """(K,) seconds from the start at each of ``states`` (K, D) (rad); strictly increasing.

    Along each segment the joint that moves most moves at :data:`JOINT_SPEED_RAD_S` times ``velocity_scaling``.
    """
    q = np.asarray(states, dtype=np.float64)
    if q.shape[0] == 0:
        return np.zeros(0)
    steps = np.max(np.abs(np.diff(q, axis=0)), axis=1) if q.shape[0] > 1 else np.zeros(0)
    seconds = np.maximum(steps / (JOINT_SPEED_RAD_S * velocity_scaling), 1e-3)
    return np.concatenate([[0.0], np.cumsum(seconds)])
