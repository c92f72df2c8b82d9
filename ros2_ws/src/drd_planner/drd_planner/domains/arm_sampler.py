"""The arm's statically valid configurations: what roadmap growth samples, and why a query state is refused.

:class:`ArmStateSampler` implements :class:`drd_planner.planner.state_sampler.StateSampler` for the arm: the
joint limits are the sampling box, a configuration is valid under the rules the roadmap was built with
(:func:`~drd_planner.domains.arm_roadmap.statically_valid`: within the joint limits, no self-collision, no
moving sphere below ``floor_z``), and :meth:`ArmStateSampler.refusal` says in one sentence why a query state is
not (joint values beyond the limits with the limits and unit, and a hint when the values look like degrees;
self-collision naming the two links; the floor). :func:`arm_state_sampler` builds one from a prior's stored
arm spec through the shared robot loader (:data:`~drd_planner.domains.arm_robot.ROBOT_MODELS`: parsed once per
description text).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray
from drd_planner.domains.arm_explain import static_reason
from drd_planner.domains.arm_params import ArmParams
from drd_planner.domains.arm_roadmap import statically_valid
from drd_planner.domains.arm_robot import ROBOT_MODELS, RobotLoader, robot_texts
from drd_planner.domains.arm_static import limits_text
from drd_planner.exceptions import GeometryError, ProblemError
from drd_planner.geometry.robot import RobotModel

__all__ = ["ArmStateSampler", "arm_state_sampler", "looks_like_degrees"]


def looks_like_degrees(robot: RobotModel, q: npt.ArrayLike) -> bool:
    """Whether the (D,) joint values ``q`` are outside the limits in radians but within them read as degrees.

    True when some |value| exceeds 2 pi (no revolute joint of a real arm turns that far) and every value
    converted from degrees lies within its limits.
    """
    config = np.asarray(q, dtype=np.float64).reshape(-1)
    if not np.any(np.abs(config) > 2.0 * math.pi):
        return False
    radians = np.radians(config)
    return bool(np.all((radians >= robot.lower) & (radians <= robot.upper)))


class ArmStateSampler:
    """Statically valid configurations of one arm model (see the module docstring).

    Args:
        robot: the arm (joint limits, spheres, self-collision pairs).
        floor_z: the roadmap's floor height (m); None: no floor rule.
    """

    def __init__(self, robot: RobotModel, *, floor_z: float | None) -> None:
        self.robot = robot
        self.floor_z = floor_z

    @property
    def lower(self) -> FloatArray:
        """(D,) lower joint limits (rad)."""
        return np.asarray(self.robot.lower, dtype=np.float64)

    @property
    def upper(self) -> FloatArray:
        """(D,) upper joint limits (rad)."""
        return np.asarray(self.robot.upper, dtype=np.float64)

    def valid(self, states: npt.ArrayLike) -> BoolArray:
        """(N,) True where an (N, D) configuration (rad) is within limits, self-collision-free, above the floor."""
        q = np.asarray(states, dtype=np.float64).reshape(-1, self.robot.dof)
        if q.shape[0] == 0:
            return np.zeros(0, dtype=bool)
        return statically_valid(self.robot, q, floor_z=self.floor_z)

    def refusal(self, state: npt.ArrayLike, label: str) -> str | None:
        """Why the (D,) query state ``label`` (``start`` or ``goal``) cannot be planned from or to; None if it can.

        One sentence per cause: joint values beyond the joint limits (each joint with its limits, in rad;
        when the values look like degrees, said so with the values in radians), self-collision (which links),
        below the floor (which link, how low, ``floor_z``).
        """
        config = np.asarray(state, dtype=np.float64).reshape(-1)
        joints = ", ".join(self.robot.chain.joint_names)
        if config.shape != (self.robot.dof,):
            return f"{label} has {config.size} joint values; the arm has {self.robot.dof} ({joints}), in rad"
        outside = limits_text(self.robot, config)
        if outside:
            hint = ""
            if looks_like_degrees(self.robot, config):
                rounded = [round(float(v), 4) for v in np.radians(config)]
                hint = (
                    f"; the values look like degrees: in radians they are {rounded}, within the limits "
                    "(joint values are radians)"
                )
            return f"{label} joint values are beyond the joint limits: {outside} (rad){hint}"
        why = static_reason(self.robot, config, floor_z=self.floor_z)
        if why:
            rounded = [round(float(v), 4) for v in config]
            return f"{label} configuration {rounded} (rad) is not valid for this prior's roadmap: {why}"
        return None


def arm_state_sampler(spec: Mapping[str, Any], *, loader: RobotLoader = ROBOT_MODELS) -> ArmStateSampler:
    """The sampler of the arm described by a prior's stored spec (its robot files and ``floor_z``).

    Raises:
        ProblemError: an invalid spec, or robot files that cannot be read or parsed.
    """
    params = ArmParams.from_spec(spec)
    try:
        robot = loader.model(*robot_texts(params.urdf_path, params.sphere_urdf_path, params.srdf_path))
    except GeometryError as exc:
        raise ProblemError(f"arm robot model: {exc}") from exc
    return ArmStateSampler(robot, floor_z=params.floor_z)
