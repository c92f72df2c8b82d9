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

__all__ = ["state_from_pose", "wrap_angle", "yaw_from_quaternion"]


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


def yaw_from_quaternion(xyzw: npt.ArrayLike) -> float:
    """The yaw (rad, about +z, in [-pi, pi)) of an (x, y, z, w) quaternion (need not be normalised).

    Raises:
        PlanningError: not four finite numbers, or a zero quaternion.
    """
    q = np.asarray(xyzw, dtype=np.float64).ravel()
    if q.shape != (4,) or not np.all(np.isfinite(q)) or not np.any(q):
        raise PlanningError(f"an orientation must be a finite non-zero (x, y, z, w) quaternion, got {q.tolist()}")
    x, y, z, w = q / np.linalg.norm(q)
    return wrap_angle(math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)))
