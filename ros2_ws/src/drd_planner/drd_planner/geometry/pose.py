"""Rigid poses with ROS quaternion order, and their conversion to FCL transforms.

ROS (``geometry_msgs/Quaternion``), scipy and this module write quaternions as ``(x, y, z, w)``; python-fcl's
``Transform(q, t)`` takes ``(w, x, y, z)``. :meth:`Pose.to_fcl` is the only place that reorders them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import fcl
import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from drd_planner.arrays import FloatArray
from drd_planner.exceptions import GeometryError

__all__ = ["Pose", "as_points", "frozen_array"]

_ORTHONORMAL_TOL = 1e-6


def frozen_array(values: npt.ArrayLike, *, shape: tuple[int, ...], what: str) -> FloatArray:
    """A read-only float64 copy of ``values`` with exactly ``shape``, all finite.

    Raises:
        GeometryError: wrong shape, not numeric, or not finite.
    """
    try:
        array = np.array(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise GeometryError(f"{what} must be numeric with shape {shape}: {exc}") from exc
    if array.shape != shape:
        raise GeometryError(f"{what} must have shape {shape}, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise GeometryError(f"{what} must be finite, got {array.tolist()}")
    array.flags.writeable = False
    return array


def as_points(points: npt.ArrayLike, *, what: str = "points") -> FloatArray:
    """``points`` as a finite float64 (K, 3) array (a single (3,) point becomes (1, 3)).

    Raises:
        GeometryError: not (K, 3) / (3,), or not finite.
    """
    try:
        array = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise GeometryError(f"{what} must be a numeric (K, 3) array: {exc}") from exc
    if array.ndim == 1 and array.shape == (3,):
        array = array.reshape(1, 3)
    if array.ndim != 2 or array.shape[1] != 3:
        raise GeometryError(f"{what} must have shape (K, 3), got {array.shape}")
    if not np.isfinite(array).all():
        raise GeometryError(f"{what} must be finite")
    return array


@dataclass(frozen=True, eq=False, init=False, repr=False)
class Pose:
    """A rigid transform from a local frame to the world frame.

    Attributes:
        position: (3,) translation in metres.
        quaternion_xyzw: (4,) unit rotation quaternion in ROS order ``(x, y, z, w)``; normalised on
            construction (a zero or non-finite quaternion raises :class:`GeometryError`).
    """

    position: FloatArray
    quaternion_xyzw: FloatArray

    def __init__(
        self, position: npt.ArrayLike = (0.0, 0.0, 0.0), quaternion_xyzw: npt.ArrayLike = (0.0, 0.0, 0.0, 1.0)
    ) -> None:
        pos = frozen_array(position, shape=(3,), what="pose position")
        quat = np.array(frozen_array(quaternion_xyzw, shape=(4,), what="pose quaternion (x, y, z, w)"))
        norm = float(np.linalg.norm(quat))
        if norm < 1e-12:
            raise GeometryError("pose quaternion (x, y, z, w) must be non-zero")
        quat /= norm
        quat.flags.writeable = False
        object.__setattr__(self, "position", pos)
        object.__setattr__(self, "quaternion_xyzw", quat)

    @classmethod
    def identity(cls) -> Pose:
        """The identity pose (origin, no rotation)."""
        return cls()

    @classmethod
    def from_matrix(cls, matrix: npt.ArrayLike) -> Pose:
        """The pose of a (4, 4) homogeneous transform (rotation block must be orthonormal, det +1).

        Raises:
            GeometryError: wrong shape, not finite, last row not (0, 0, 0, 1), or not a rotation.
        """
        m = frozen_array(matrix, shape=(4, 4), what="pose matrix")
        if not np.allclose(m[3], (0.0, 0.0, 0.0, 1.0)):
            raise GeometryError(f"pose matrix last row must be (0, 0, 0, 1), got {m[3].tolist()}")
        return cls(m[:3, 3], _quaternion_of(m[:3, :3]))

    @classmethod
    def from_rotation(cls, rotation: npt.ArrayLike, position: npt.ArrayLike = (0.0, 0.0, 0.0)) -> Pose:
        """The pose with (3, 3) rotation matrix ``rotation`` and (3,) ``position`` in metres.

        Raises:
            GeometryError: not a proper rotation matrix.
        """
        return cls(position, _quaternion_of(frozen_array(rotation, shape=(3, 3), what="rotation matrix")))

    def rotation(self) -> FloatArray:
        """(3, 3) rotation matrix (columns are the local axes in world coordinates)."""
        matrix: FloatArray = Rotation.from_quat(self.quaternion_xyzw).as_matrix()
        return matrix

    def matrix(self) -> FloatArray:
        """(4, 4) homogeneous transform, local to world."""
        out = np.eye(4)
        out[:3, :3] = self.rotation()
        out[:3, 3] = self.position
        return out

    def to_fcl(self) -> fcl.Transform:
        """The python-fcl transform of this pose (FCL wants the quaternion as (w, x, y, z))."""
        x, y, z, w = self.quaternion_xyzw
        return fcl.Transform(np.array([w, x, y, z]), np.array(self.position))

    def transform_points(self, points: npt.ArrayLike) -> FloatArray:
        """(K, 3) world coordinates of (K, 3) local ``points`` (metres)."""
        local = as_points(points)
        out: FloatArray = local @ self.rotation().T + self.position
        return out

    def compose(self, other: Pose) -> Pose:
        """The pose ``self * other``: ``other`` expressed in the frame of ``self``."""
        return Pose.from_matrix(self.matrix() @ other.matrix())

    def inverse(self) -> Pose:
        """The inverse transform (world to local)."""
        rot = self.rotation()
        return Pose.from_rotation(rot.T, -rot.T @ self.position)

    def _key(self) -> tuple[bytes, bytes]:
        return self.position.tobytes(), self.quaternion_xyzw.tobytes()

    def __eq__(self, other: Any) -> bool:
        return isinstance(other, Pose) and self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())

    def __repr__(self) -> str:
        return f"Pose(position={self.position.tolist()}, quaternion_xyzw={self.quaternion_xyzw.tolist()})"


def _quaternion_of(rotation: FloatArray) -> FloatArray:
    """(4,) (x, y, z, w) quaternion of a (3, 3) proper rotation matrix; GeometryError otherwise."""
    if not np.allclose(rotation @ rotation.T, np.eye(3), atol=_ORTHONORMAL_TOL) or np.linalg.det(rotation) <= 0:
        raise GeometryError("rotation block must be orthonormal with determinant +1")
    quat: FloatArray = Rotation.from_matrix(rotation).as_quat()
    return quat
