"""Batched forward kinematics of a serial chain: (N, D) joint values -> (N, D + 1, 4, 4) frame poses.

Each joint's local transform ``origin_i @ motion_i(q_i)`` is affine in two scalar functions of q_i
(Rodrigues: ``R(q) = I + sin q K + (1 - cos q) K^2``; prismatic: ``t(q) = q a``), so with three
constant 4x4 matrices per joint it is ``A_i + f1(q_i) B_i + f2(q_i) C_i``; the frames are then one
batched matrix product per joint. Everything is vectorised over the N configurations.

Units: metres and radians.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.exceptions import GeometryError
from drd_planner.geometry.urdf_model import KinematicChain

__all__ = ["ForwardKinematics"]


def _skew(axis: FloatArray) -> FloatArray:
    """(3, 3) cross-product matrix of a (3,) vector."""
    x, y, z = axis
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


class ForwardKinematics:
    """Forward kinematics of one :class:`KinematicChain`, vectorised over configurations.

    Args:
        chain: the chain (joint origins, axes, types, link offsets).
    """

    def __init__(self, chain: KinematicChain) -> None:
        self.chain = chain
        dof = chain.dof
        self._a = chain.joint_origins.copy()
        self._b = np.zeros((dof, 4, 4))
        self._c = np.zeros((dof, 4, 4))
        revolute = np.array([t == "revolute" for t in chain.joint_types])
        for i in range(dof):
            rot = chain.joint_origins[i, :3, :3]
            if revolute[i]:
                k = _skew(chain.axes[i])
                self._b[i, :3, :3] = rot @ k
                self._c[i, :3, :3] = rot @ k @ k
            else:
                self._b[i, :3, 3] = rot @ chain.axes[i]
        self._revolute = revolute

    @property
    def dof(self) -> int:
        """D, the number of joints."""
        return self.chain.dof

    def as_configurations(self, q: npt.ArrayLike) -> FloatArray:
        """``q`` as a finite (N, D) float64 array ((D,) is promoted to (1, D)).

        Raises:
            GeometryError: wrong shape or non-finite values.
        """
        qa = np.asarray(q, dtype=np.float64)
        if qa.ndim == 1:
            qa = qa[None, :]
        if qa.ndim != 2 or qa.shape[1] != self.dof:
            raise GeometryError(f"configurations must have shape (N, {self.dof}), got {qa.shape}")
        if not np.all(np.isfinite(qa)):
            raise GeometryError("configurations must be finite")
        return qa

    def joint_locals(self, q: npt.ArrayLike) -> FloatArray:
        """(N, D, 4, 4) transform of moving frame i in moving frame i - 1 for each configuration."""
        qa = self.as_configurations(q)
        f1 = np.where(self._revolute, np.sin(qa), qa)
        f2 = np.where(self._revolute, 1.0 - np.cos(qa), 0.0)
        out: FloatArray = self._a + f1[:, :, None, None] * self._b + f2[:, :, None, None] * self._c
        return out

    def frames(self, q: npt.ArrayLike) -> FloatArray:
        """(N, D + 1, 4, 4) poses of the moving frames in the root link's frame (frame 0 = identity)."""
        local = self.joint_locals(q)
        n = local.shape[0]
        out = np.empty((n, self.dof + 1, 4, 4))
        out[:, 0] = np.eye(4)
        out[:, 1] = local[:, 0]
        for i in range(1, self.dof):
            np.matmul(out[:, i], local[:, i], out=out[:, i + 1])
        return out

    def link_poses(self, q: npt.ArrayLike) -> FloatArray:
        """(N, L, 4, 4) pose of every URDF link (order of ``chain.link_names``) in the root frame."""
        frames = self.frames(q)
        out: FloatArray = frames[:, self.chain.link_frames] @ self.chain.link_offsets
        return out

    def link_pose(self, q: npt.ArrayLike, link: str) -> FloatArray:
        """(N, 4, 4) pose of one link in the root frame."""
        i = self.chain.link_index(link)
        frames = self.frames(q)
        out: FloatArray = frames[:, self.chain.link_frames[i]] @ self.chain.link_offsets[i]
        return out

    def point_map(self, frame_index: npt.ArrayLike, local: npt.ArrayLike) -> FloatArray:
        """(F * 16, S * 3) matrix M such that ``frames.reshape(N, -1) @ M`` are the (N, S * 3) world points.

        Point s, coordinate i is ``sum_j T_f(s)[i, j] * p_s[j]`` with p_s homogeneous: a linear function of
        the flattened (N, F, 4, 4) frame poses, so all points of all configurations come from one product.

        Args:
            frame_index: (S,) frame (0..D) of each point.
            local: (S, 3) point positions in their frames (m).
        """
        frames_of = np.asarray(frame_index, dtype=np.int64).reshape(-1)
        points = np.asarray(local, dtype=np.float64).reshape(-1, 3)
        if points.shape[0] != frames_of.shape[0]:
            raise GeometryError("point_map needs one frame index per point")
        num_frames = self.dof + 1
        if frames_of.size and (frames_of.min() < 0 or frames_of.max() >= num_frames):
            raise GeometryError(f"frame indices must lie in [0, {num_frames})")
        count = points.shape[0]
        out = np.zeros((num_frames, 4, 4, count, 3))
        homogeneous = np.concatenate([points, np.ones((count, 1))], axis=1)
        for s in range(count):
            for i in range(3):
                out[frames_of[s], i, :, s, i] = homogeneous[s]
        return out.reshape(num_frames * 16, count * 3)

    @staticmethod
    def apply_point_map(frames: FloatArray, point_map: FloatArray) -> FloatArray:
        """(N, S, 3) world points from (N, F, 4, 4) frames and a :meth:`point_map` (metres)."""
        n = frames.shape[0]
        flat: FloatArray = frames.reshape(n, -1) @ point_map
        return flat.reshape(n, -1, 3)
