"""States that are poses: ``(x, y, z, heading)`` vectors (the helicopter's), made from a position and a yaw.

Domains own this conversion (:meth:`~drd_planner.domains.online.OnlineDomain.state_from_position`); the request
readers in :mod:`drd_planner.planning.requests` use it for odometry and goal poses.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.exceptions import PlanningError

__all__ = ["state_from_pose", "wrap_angle"]


def wrap_angle(angle: float) -> float:
    """``angle`` (rad) wrapped to [-pi, pi)."""
    return float((angle + math.pi) % (2.0 * math.pi) - math.pi)


def state_from_pose(position: npt.ArrayLike, yaw: float) -> FloatArray:
    """(4,) helicopter state (x, y, z in metres, heading in rad in [-pi, pi)) of a position and a yaw.

    Raises:
        PlanningError: the position is not three finite numbers, or the yaw is not finite.
    """
    xyz = np.asarray(position, dtype=np.float64).ravel()
    if xyz.shape != (3,) or not np.all(np.isfinite(xyz)):
        raise PlanningError(f"a position must be three finite numbers (m), got {xyz.tolist()}")
    if not math.isfinite(float(yaw)):
        raise PlanningError(f"a yaw must be a finite angle (rad), got {yaw}")
    return np.array([xyz[0], xyz[1], xyz[2], wrap_angle(float(yaw))], dtype=np.float64)
