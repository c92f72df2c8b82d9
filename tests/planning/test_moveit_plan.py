"""GetMotionPlan requests read, outcomes coded as MoveIt does, trajectories timed (no ROS needed)."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from drd_planner.core.status import PlanCause, PlanStatus
from drd_planner.planning.moveit_plan import (
    JOINT_SPEED_RAD_S,
    MOVEIT_CODES,
    MotionRequest,
    MoveItError,
    moveit_error,
    read_motion_request,
    timed_waypoints,
)
from drd_planner.planning.plan_outcome import PlanOutcome
from drd_planner.planning.session_plan import SessionPlan

#: Stand-ins for message objects (fields as attributes).
Msg = SimpleNamespace

JOINTS = ("j1", "j2")


def constraints(joints: dict[str, float] | None = None, **other: list[Any]) -> Msg:
    return Msg(
        joint_constraints=[Msg(joint_name=n, position=p) for n, p in (joints or {}).items()],
        position_constraints=other.get("position", []),
        orientation_constraints=other.get("orientation", []),
        visibility_constraints=other.get("visibility", []),
    )


def request(
    goals: list[Msg], start: dict[str, float] | None = None, *, path: Msg | None = None, scaling: float = 0.0
) -> Msg:
    names, positions = (list(start), list(start.values())) if start else ([], [])
    return Msg(
        goal_constraints=goals,
        start_state=Msg(joint_state=Msg(name=names, position=positions)),
        path_constraints=path or constraints(),
        trajectory_constraints=Msg(constraints=[]),
        max_velocity_scaling_factor=scaling,
    )


def test_joint_goal_and_start_in_the_arm_order() -> None:
    read = read_motion_request(request([constraints({"j2": 2.0, "j1": 1.0})], {"j2": 0.5, "j1": -0.5}), JOINTS)
    assert isinstance(read, MotionRequest)
    assert read.goal.joints is not None
    assert read.goal.joints.tolist() == [1.0, 2.0]
    assert read.start is not None
    assert read.start.joints is not None
    assert read.start.joints.tolist() == [-0.5, 0.5]
    assert read.velocity_scaling == 1.0  # 0: MoveIt's default


def test_empty_start_is_the_robot_state_and_the_first_joint_set_is_the_goal() -> None:
    goals = [constraints(position=[Msg()]), constraints({"j1": 0.0, "j2": 0.1})]
    read = read_motion_request(request(goals, scaling=0.5), JOINTS)
    assert isinstance(read, MotionRequest)
    assert read.start is None
    assert read.velocity_scaling == 0.5
    assert read.goal.joints is not None
    assert read.goal.joints.tolist() == [0.0, 0.1]


@pytest.mark.parametrize(
    ("req", "name", "text"),
    [
        (request([]), "INVALID_GOAL_CONSTRAINTS", "no goal constraints"),
        (request([constraints(position=[Msg()])]), "INVALID_GOAL_CONSTRAINTS", "inverse kinematics"),
        (request([constraints({"j1": 0.0})]), "INVALID_GOAL_CONSTRAINTS", "missing joints ['j2']"),
        (request([constraints({"j1": 0, "j2": 0})], {"j1": 0.0}), "INVALID_ROBOT_STATE", "missing joints"),
        (
            request([constraints({"j1": 0, "j2": 0})], path=constraints({"j1": 0.0})),
            "INVALID_GOAL_CONSTRAINTS",
            "path constraints",
        ),
        (request([constraints({"j1": 0, "j2": 0})], scaling=2.0), "FAILURE", "max_velocity_scaling_factor"),
    ],
)
def test_refused_requests_have_moveit_codes(req: Msg, name: str, text: str) -> None:
    read = read_motion_request(req, JOINTS)
    assert isinstance(read, MoveItError)
    assert read.name == name
    assert text in read.text
    assert read.code == MOVEIT_CODES[name]


def result(status: PlanStatus, message: str = "", cause: PlanCause | None = None) -> SessionPlan:
    return SessionPlan(status=status, message=message, map_version=1, prior="t", cause=cause)


@pytest.mark.parametrize(
    ("outcome", "name"),
    [
        (PlanOutcome(result=result(PlanStatus.FOUND)), "SUCCESS"),
        (
            PlanOutcome(result=result(PlanStatus.NO_PATH, "the start state is blocked", PlanCause.START_BLOCKED)),
            "START_STATE_IN_COLLISION",
        ),
        (
            PlanOutcome(result=result(PlanStatus.NO_PATH, "the goal state is blocked", PlanCause.GOAL_BLOCKED)),
            "GOAL_IN_COLLISION",
        ),
        (PlanOutcome(result=result(PlanStatus.BUDGET_EXHAUSTED, "10 checks", PlanCause.CHECK_BUDGET)), "TIMED_OUT"),
        (PlanOutcome(result=result(PlanStatus.NO_PATH, "every path blocked")), "PLANNING_FAILED"),
        (PlanOutcome(refusal="no joint_states yet", refused="start"), "INVALID_ROBOT_STATE"),
        (PlanOutcome(refusal="no maps", refused="maps"), "FAILURE"),
    ],
)
def test_outcomes_map_to_moveit_codes(outcome: PlanOutcome, name: str) -> None:
    error = moveit_error(outcome)
    assert error.name == name
    assert (error.code == 1) == (name == "SUCCESS")


def test_timing_moves_the_fastest_joint_at_the_scaled_speed() -> None:
    states = np.array([[0.0, 0.0], [0.5, 0.1], [0.5, -0.9], [0.5, -0.9]])
    seconds = timed_waypoints(states, 0.5)
    speed = JOINT_SPEED_RAD_S * 0.5
    np.testing.assert_allclose(seconds[:3], [0.0, 0.5 / speed, 1.5 / speed])
    assert np.all(np.diff(seconds) > 0)  # a repeated state still advances time
    assert timed_waypoints(np.zeros((0, 2))).shape == (0,)
