"""Checks of a ``robot_description`` for what planning needs: its size before parsing, its numbers after.

A description is parsed into a self-collision table that grows with links^2 and spheres^2, so
:func:`check_description_size` bounds its bytes, links, collision spheres and origin numbers (a
:class:`~drd_planner.geometry.map_limits.MapLimits`) with the standard XML parser before the model is
built. :func:`check_robot_coordinates` refuses a parsed model whose joint and link frames or collision spheres are
not finite or lie beyond ``max_coordinate`` (a URDF origin of 1e308 composes to infinity), which would make
every later check fail. Refusals are :class:`~drd_planner.exceptions.ProblemError` naming the limit's parameter.
"""

from __future__ import annotations

import numpy as np

from drd_planner.exceptions import GeometryError, ProblemError
from drd_planner.geometry.map_limits import MapLimits
from drd_planner.geometry.robot import RobotModel
from drd_planner.geometry.urdf_model import description_summary

__all__ = ["check_description_size", "check_robot_coordinates"]


def check_description_size(urdf: str, limits: MapLimits) -> None:
    """Refuse a URDF text over ``limits`` before any model is built.

    Checks its bytes, then (standard XML parser) its origin coordinates and sphere radii against
    ``max_coordinate`` and its links and collision spheres against ``max_robot_links`` and ``max_robot_spheres``.

    Raises:
        ProblemError: over a limit (the text names it and its parameter), or not well-formed XML.
    """
    size = len(urdf) if len(urdf) > limits.max_message_bytes else len(urdf.encode("utf-8", "replace"))
    if size > limits.max_message_bytes:
        raise ProblemError(limits.refusal("max_message_bytes", f"robot_description has {size} bytes"))
    try:
        links, spheres, largest = description_summary(urdf)
    except GeometryError as exc:
        raise ProblemError(f"robot_description: {exc}") from exc
    if largest > limits.max_coordinate:
        what = f"robot_description origins or sphere radii reach {largest:.6g} m in absolute value"
        raise ProblemError(limits.refusal("max_coordinate", what))
    if links > limits.max_robot_links:
        raise ProblemError(limits.refusal("max_robot_links", f"robot_description has {links} links"))
    if spheres > limits.max_robot_spheres:
        raise ProblemError(limits.refusal("max_robot_spheres", f"robot_description has {spheres} collision spheres"))


def check_robot_coordinates(robot: RobotModel, limits: MapLimits) -> None:
    """Refuse a model whose frames or spheres are not finite or reach beyond ``limits.max_coordinate`` (m).

    Checks the (D, 4, 4) joint origins, the (L, 4, 4) link offsets in their moving frames, and the (S, 3)
    sphere centres and (S,) radii.

    Raises:
        ProblemError: the text says which numbers and names the parameter.
    """
    chain, spheres = robot.chain, robot.spheres
    frames = np.concatenate([chain.joint_origins.reshape(-1), chain.link_offsets.reshape(-1)])
    balls = np.concatenate([spheres.centres.reshape(-1), spheres.radii])
    for what, values in (("joint and link origins", frames), ("collision spheres", balls)):
        if not np.isfinite(values).all():
            raise ProblemError(f"robot_description {what} are not finite (an origin too large to compose?)")
        problem = limits.coordinate_problem(values, f"robot_description {what}")
        if problem is not None:
            raise ProblemError(problem)
