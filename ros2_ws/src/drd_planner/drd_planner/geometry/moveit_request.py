"""MoveIt MotionPlanRequest YAML (as written by MotionBenchMaker) -> named joint states of its start and goals.

Reads ``start_state.joint_state`` (``name`` and ``position`` lists) and, per entry of ``goal_constraints``,
its ``joint_constraints`` (``joint_name`` and ``position`` each) with the bounded safe loader of
:mod:`~drd_planner.geometry.moveit_yaml`. Positions are in
radians (revolute joints) or metres (prismatic joints), as in MoveIt.

:func:`joint_vector` puts such a named state in a robot's joint order: a joint the robot plans but the state
lacks is always refused; joints the robot does not plan are refused in goals (a constraint that could not be
honoured) and ignored in the start state (a MoveIt robot state holds every joint, the gripper's too, as
``joint_states`` does).

Anything else is refused with a :class:`GeometryError` naming the source: goals with position, orientation or
visibility constraints (they need inverse kinematics), a start state without joint positions, names and
positions of different lengths, repeated names and non-finite numbers.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.exceptions import GeometryError
from drd_planner.geometry.moveit_yaml import load_yaml, quoted, read_yaml_text

__all__ = ["RequestStates", "joint_vector", "parse_motion_plan_request", "read_motion_plan_request"]

#: Constraint kinds a goal may not hold (only joint constraints give a joint state without IK).
_OTHER_CONSTRAINTS = ("position_constraints", "orientation_constraints", "visibility_constraints")

#: A joint state by joint name (rad or m).
NamedState = Mapping[str, float]


@dataclass(frozen=True)
class RequestStates:
    """The joint states a MotionPlanRequest names.

    Attributes:
        source: where it was read from (a file name), for messages.
        start: the start state's joints by name (None: the request has no ``start_state.joint_state``).
        goals: one named state per goal constraint, in file order.
    """

    source: str
    start: NamedState | None
    goals: tuple[NamedState, ...]


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(float(value)):
        raise GeometryError(f"{where}: joint positions must be finite numbers, got {quoted(value)}")
    return float(value)


def _start_state(doc: Mapping[str, Any], source: str) -> NamedState | None:
    """``start_state.joint_state`` as name -> position (None when absent or empty)."""
    state = doc.get("start_state")
    joints = state.get("joint_state") if isinstance(state, Mapping) else None
    if not isinstance(joints, Mapping):
        return None
    names, positions = joints.get("name") or [], joints.get("position") or []
    if not isinstance(names, list) or not isinstance(positions, list):
        raise GeometryError(f"{source}: start_state.joint_state name and position must be lists")
    if not names and not positions:
        return None
    if len(names) != len(positions):
        raise GeometryError(f"{source}: start_state.joint_state has {len(names)} names but {len(positions)} positions")
    where = f"{source}: start_state.joint_state"
    out: dict[str, float] = {}
    for name, position in zip(names, positions, strict=True):
        if str(name) in out:
            raise GeometryError(f"{where} names joint {quoted(name)} twice")
        out[str(name)] = _number(position, where)
    return out


def _goal(constraints: Any, k: int, source: str) -> NamedState:
    """The named joint state of goal constraint ``k``."""
    where = f"{source}: goal_constraints[{k}]"
    if not isinstance(constraints, Mapping):
        raise GeometryError(f"{where} must be a mapping")
    for key in _OTHER_CONSTRAINTS:
        if constraints.get(key):
            raise GeometryError(
                f"{where} has {key}; only joint_constraints goals are supported (they need no inverse kinematics)"
            )
    joints = constraints.get("joint_constraints") or []
    if not isinstance(joints, list) or not joints:
        raise GeometryError(f"{where} has no joint_constraints")
    out: dict[str, float] = {}
    for item in joints:
        if not isinstance(item, Mapping) or "joint_name" not in item or "position" not in item:
            raise GeometryError(f"{where}: each joint constraint needs joint_name and position, got {quoted(item)}")
        name = str(item["joint_name"])
        if name in out:
            raise GeometryError(f"{where} constrains joint {quoted(name)} twice")
        out[name] = _number(item["position"], f"{where} joint {quoted(name)}")
    return out


def parse_motion_plan_request(text: str, *, source: str = "<string>") -> RequestStates:
    """The start and goal joint states of a MotionPlanRequest YAML document.

    Raises:
        GeometryError: invalid YAML, no goal constraints, or anything the module docstring lists; the
            message names ``source``.
    """
    doc = load_yaml(text, source=source)
    if not isinstance(doc, Mapping):
        raise GeometryError(f"{source}: a motion plan request must be a YAML mapping")
    goals = doc.get("goal_constraints") or []
    if not isinstance(goals, list) or not goals:
        raise GeometryError(f"{source}: no goal_constraints")
    return RequestStates(source, _start_state(doc, source), tuple(_goal(g, k, source) for k, g in enumerate(goals)))


def read_motion_plan_request(path: str | Path) -> RequestStates:
    """The start and goal joint states of a MotionPlanRequest YAML file (see :func:`parse_motion_plan_request`).

    Raises:
        GeometryError: unreadable file or invalid content.
    """
    return parse_motion_plan_request(read_yaml_text(path, "motion plan request"), source=str(path))


def joint_vector(state: NamedState, joint_names: Sequence[str], *, where: str, allow_extra: bool = False) -> FloatArray:
    """(D,) the positions of ``state`` in the order of ``joint_names`` (D joints).

    Args:
        state: joint name -> position.
        joint_names: the robot's planned joints, in order.
        where: what the state is (a file and part of it), for messages.
        allow_extra: ignore joints that are not in ``joint_names`` (a start state); else refuse them.

    Raises:
        GeometryError: a joint of ``joint_names`` is missing, or (without ``allow_extra``) the state has
            joints the robot does not plan; the message names them and the robot's joints.
    """
    missing = [name for name in joint_names if name not in state]
    extra = [] if allow_extra else sorted(set(state) - set(joint_names))
    if missing or extra:
        parts = ([f"lacks joints {missing}"] if missing else []) + ([f"has joints {extra}"] if extra else [])
        raise GeometryError(
            f"{where} {' and '.join(parts)}; the robot plans joints {list(joint_names)} "
            "(a request must name exactly these)"
        )
    return np.array([state[name] for name in joint_names], dtype=np.float64)
