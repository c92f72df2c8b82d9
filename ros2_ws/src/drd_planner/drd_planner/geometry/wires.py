"""Power-line wires: a parabolic sag between two attachment points, and a capsule chain for FCL.

The wire hangs as ``p(t) = start + t (end - start) - 4 sag t (1 - t) z``, t in [0, 1]: the chord, lowered by a
parabola that is ``sag`` metres below the chord at mid-span (t = 1/2) and zero at the towers. For towers of
equal height mid-span is also the lowest point. A chain of n capsules through the points at t = k/n
approximates the curve; the chord of each piece is at most ``sag / n**2`` metres from the curve (vertically),
and :meth:`Wire.capsule_chain` adds that to the capsule radius, so the chain contains the whole wire.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.exceptions import GeometryError
from drd_planner.geometry.pose import Pose, frozen_array
from drd_planner.geometry.shapes import Capsule

__all__ = ["Wire", "capsule_between"]


@dataclass(frozen=True, eq=False, init=False, repr=False)
class Wire:
    """A sagging wire between two attachment points.

    Attributes:
        start: (3,) first attachment point in metres.
        end: (3,) second attachment point in metres (distinct from ``start``).
        sag: metres (>= 0, finite) by which the wire hangs below the chord at mid-span.
        diameter: wire diameter in metres (> 0, finite).
    """

    start: FloatArray
    end: FloatArray
    sag: float
    diameter: float

    def __init__(self, start: npt.ArrayLike, end: npt.ArrayLike, sag: float, diameter: float) -> None:
        first = frozen_array(start, shape=(3,), what="wire start")
        last = frozen_array(end, shape=(3,), what="wire end")
        if float(np.linalg.norm(last - first)) <= 0.0:
            raise GeometryError("wire start and end must differ")
        sag_m, diameter_m = float(sag), float(diameter)
        if not math.isfinite(sag_m) or sag_m < 0.0:
            raise GeometryError(f"wire sag must be finite and >= 0, got {sag!r}")
        if not math.isfinite(diameter_m) or diameter_m <= 0.0:
            raise GeometryError(f"wire diameter must be finite and > 0, got {diameter!r}")
        object.__setattr__(self, "start", first)
        object.__setattr__(self, "end", last)
        object.__setattr__(self, "sag", sag_m)
        object.__setattr__(self, "diameter", diameter_m)

    def __eq__(self, other: Any) -> bool:
        return isinstance(other, Wire) and self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())

    def _key(self) -> tuple[bytes, bytes, float, float]:
        return self.start.tobytes(), self.end.tobytes(), self.sag, self.diameter

    def __repr__(self) -> str:
        return f"Wire(start={self.start.tolist()}, end={self.end.tolist()}, sag={self.sag}, diameter={self.diameter})"

    def point_at(self, t: npt.ArrayLike) -> FloatArray:
        """(K, 3) points (metres) of the wire at (K,) parameters ``t`` in [0, 1] (0 = start, 1 = end)."""
        ts = np.atleast_1d(np.asarray(t, dtype=np.float64))
        if ts.ndim != 1 or np.any(~np.isfinite(ts)) or np.any(ts < 0.0) or np.any(ts > 1.0):
            raise GeometryError("wire parameters t must be a 1-D array of numbers in [0, 1]")
        points: FloatArray = self.start + ts[:, None] * (self.end - self.start)
        points[:, 2] -= 4.0 * self.sag * ts * (1.0 - ts)
        return points

    def points(self, n: int) -> FloatArray:
        """(n, 3) points (metres) at n evenly spaced parameters from start to end inclusive (n >= 2)."""
        if int(n) != n or n < 2:
            raise GeometryError(f"wire points need n >= 2, got {n!r}")
        return self.point_at(np.linspace(0.0, 1.0, int(n)))

    def default_segments(self) -> int:
        """Capsules needed so the chord error ``sag / n**2`` is at most the wire radius (at least 1)."""
        radius = self.diameter / 2.0
        return max(1, math.ceil(math.sqrt(self.sag / radius))) if self.sag > 0 else 1

    def capsule_chain(self, segments: int | None = None) -> list[tuple[Capsule, Pose]]:
        """Capsules (with world poses) whose union contains the wire.

        Capsule k joins the wire points at t = k/n and (k+1)/n; its radius is ``diameter / 2 + sag / n**2``
        (the wire radius plus the largest gap between the chord and the parabola).

        Args:
            segments: number n of capsules (>= 1); default :meth:`default_segments`.
        """
        n = self.default_segments() if segments is None else segments
        if int(n) != n or n < 1:
            raise GeometryError(f"wire capsule chain needs segments >= 1, got {segments!r}")
        n = int(n)
        radius = self.diameter / 2.0 + self.sag / n**2
        return [capsule_between(a, b, radius) for a, b in itertools.pairwise(self.points(n + 1))]


def capsule_between(a: npt.ArrayLike, b: npt.ArrayLike, radius: float) -> tuple[Capsule, Pose]:
    """The capsule of ``radius`` metres whose segment joins the (3,) points ``a`` and ``b`` (metres), with its pose.

    Raises:
        GeometryError: ``a`` and ``b`` coincide or ``radius`` is not > 0.
    """
    first, second = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    axis = second - first
    length = float(np.linalg.norm(axis))
    if not length > 0.0:
        raise GeometryError("a capsule needs two distinct end points")
    return Capsule(radius, length), Pose.from_rotation(_frame_with_z(axis / length), (first + second) / 2.0)


def _frame_with_z(z_axis: FloatArray) -> FloatArray:
    """(3, 3) rotation matrix whose third column is the unit vector ``z_axis``."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(z_axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x_axis = np.cross(helper, z_axis)
    x_axis /= np.linalg.norm(x_axis)
    y_axis = np.cross(z_axis, x_axis)
    return np.column_stack([x_axis, y_axis, z_axis])
