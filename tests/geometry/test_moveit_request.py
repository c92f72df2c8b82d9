"""Tests of the MotionPlanRequest reader: start and joint-goal states, joint order, refusals."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from drd_planner.exceptions import GeometryError
from drd_planner.geometry.moveit_request import (
    joint_vector,
    parse_motion_plan_request,
    read_motion_plan_request,
)

JOINTS = ("j1", "j2", "j3")

REQUEST = """
group_name: arm
start_state:
  joint_state:
    name: [j1, j2, j3, finger]
    position: [0.1, -0.2, 0.3, 0.04]
goal_constraints:
  - joint_constraints:
      - joint_name: j3
        position: 1.5
      - position: -1.0
        joint_name: j1
      - joint_name: j2
        position: 0.25
  - joint_constraints:
      - {joint_name: j1, position: 0}
      - {joint_name: j2, position: 0}
      - {joint_name: j3, position: 2}
"""


def test_start_and_goals_are_read_by_name() -> None:
    states = parse_motion_plan_request(REQUEST, source="r.yaml")
    assert states.source == "r.yaml"
    assert states.start == {"j1": 0.1, "j2": -0.2, "j3": 0.3, "finger": 0.04}
    assert len(states.goals) == 2
    assert states.goals[0] == {"j3": 1.5, "j1": -1.0, "j2": 0.25}


def test_joint_vector_follows_the_robot_order() -> None:
    states = parse_motion_plan_request(REQUEST)
    assert states.start is not None
    start = joint_vector(states.start, JOINTS, where="start", allow_extra=True)
    assert np.array_equal(start, [0.1, -0.2, 0.3])
    assert np.array_equal(joint_vector(states.goals[0], JOINTS, where="goal"), [-1.0, 0.25, 1.5])
    assert np.array_equal(joint_vector(states.goals[0], ("j3", "j1", "j2"), where="goal"), [1.5, -1.0, 0.25])


def test_missing_and_extra_joints_are_named() -> None:
    states = parse_motion_plan_request(REQUEST)
    assert states.start is not None
    with pytest.raises(GeometryError, match=r"r\.yaml start has joints \['finger'\]; the robot plans joints"):
        joint_vector(states.start, JOINTS, where="r.yaml start")
    with pytest.raises(
        GeometryError, match=r"goal lacks joints \['j4'\]; the robot plans joints \['j1', 'j2', 'j3', 'j4'\]"
    ):
        joint_vector(states.goals[0], (*JOINTS, "j4"), where="goal")
    with pytest.raises(GeometryError, match=r"lacks joints \['j0'\] and has joints \['j3'\]"):
        joint_vector(states.goals[0], ("j0", "j1", "j2"), where="goal")


def test_a_request_without_a_start_state() -> None:
    text = "goal_constraints:\n  - joint_constraints:\n      - {joint_name: j1, position: 0.5}\n"
    states = parse_motion_plan_request(text)
    assert states.start is None
    assert states.goals == ({"j1": 0.5},)
    empty = "start_state:\n  joint_state: {name: [], position: []}\n" + text
    assert parse_motion_plan_request(empty).start is None


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[1, 2", "not valid YAML"),
        ("- a list", "must be a YAML mapping"),
        ("group_name: arm\n", "no goal_constraints"),
        (
            "goal_constraints:\n  - position_constraints: [{link_name: hand}]\n",
            r"goal_constraints\[0\] has position_constraints; only joint_constraints goals are supported",
        ),
        ("goal_constraints:\n  - joint_constraints: []\n", r"goal_constraints\[0\] has no joint_constraints"),
        (
            "goal_constraints:\n  - joint_constraints:\n      - {joint_name: j1}\n",
            "each joint constraint needs joint_name and position",
        ),
        (
            "goal_constraints:\n  - joint_constraints:\n      - {joint_name: j1, position: .nan}\n",
            "joint positions must be finite numbers",
        ),
        (
            "goal_constraints:\n  - joint_constraints:\n      - {joint_name: j1, position: 0}\n"
            "      - {joint_name: j1, position: 1}\n",
            "constrains joint 'j1' twice",
        ),
        (
            "start_state:\n  joint_state: {name: [a, b], position: [0]}\ngoal_constraints:\n"
            "  - joint_constraints: [{joint_name: a, position: 0}]\n",
            "has 2 names but 1 positions",
        ),
        (
            "start_state:\n  joint_state: {name: [a, a], position: [0, 1]}\ngoal_constraints:\n"
            "  - joint_constraints: [{joint_name: a, position: 0}]\n",
            "names joint 'a' twice",
        ),
    ],
)
def test_malformed_requests_are_refused(text: str, message: str) -> None:
    with pytest.raises(GeometryError, match=message):
        parse_motion_plan_request(text, source="bad.yaml")


def test_reading_a_file(tmp_path: Path) -> None:
    path = tmp_path / "request0001.yaml"
    path.write_text(REQUEST)
    assert read_motion_plan_request(path).goals[1] == {"j1": 0.0, "j2": 0.0, "j3": 2.0}
    with pytest.raises(GeometryError, match="cannot read motion plan request"):
        read_motion_plan_request(tmp_path / "missing.yaml")
