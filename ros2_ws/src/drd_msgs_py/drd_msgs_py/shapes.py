"""Plain data of map messages: poses, marker shapes and terrain grids, as the messages carry them.

These are what :mod:`drd_msgs_py.obstacles` and :mod:`drd_msgs_py.terrain` read from (and write to)
messages; a consumer turns them into its own geometry (drd_planner: ``planning.map_intake``). Lengths in
metres, angles in radians; poses map a marker's local frame to the message frame.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from drd_msgs_py.arrays import FloatArray, IntArray

__all__ = [
    "BoxData",
    "CylinderData",
    "GridLike",
    "HeightGrid",
    "LineStripData",
    "MeshData",
    "PoseData",
    "ShapeData",
    "SphereData",
]


@dataclass(frozen=True)
class PoseData:
    """A ``geometry_msgs/Pose``: position (x, y, z) metres and quaternion (x, y, z, w), finite, norm near 1."""

    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    quaternion_xyzw: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)


@dataclass(frozen=True)
class BoxData:
    """A CUBE marker: edge lengths (x, y, z) metres, centred on its pose."""

    size: tuple[float, float, float]


@dataclass(frozen=True)
class SphereData:
    """A SPHERE marker: radius in metres."""

    radius: float


@dataclass(frozen=True)
class CylinderData:
    """A CYLINDER marker along its local z: radius and length (metres), centred on its pose."""

    radius: float
    length: float


@dataclass(frozen=True, eq=False)
class MeshData:
    """A TRIANGLE_LIST marker: (V, 3) vertices (metres, local frame) and (F, 3) vertex indices per triangle."""

    vertices: FloatArray
    faces: IntArray


@dataclass(frozen=True, eq=False)
class LineStripData:
    """A LINE_STRIP marker: a wire of ``diameter`` metres through (K >= 2, 3) ``points`` in the local frame."""

    points: FloatArray
    diameter: float


#: One marker's shape.
ShapeData = BoxData | SphereData | CylinderData | MeshData | LineStripData


@dataclass(frozen=True, eq=False)
class HeightGrid:
    """An organized terrain cloud as a grid.

    Attributes:
        origin: (x0, y0) metres of grid point (0, 0).
        cell_size: spacing of the square grid, metres.
        heights: (rows, cols) z in metres; row i at y0 + i * cell_size, column j at x0 + j * cell_size;
            NaN = unknown.
    """

    origin: tuple[float, float]
    cell_size: float
    heights: FloatArray

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols) of the grid."""
        return int(self.heights.shape[0]), int(self.heights.shape[1])


class GridLike(Protocol):
    """What a terrain cloud is written from: a :class:`HeightGrid`, or any heightfield with these members."""

    @property
    def origin(self) -> tuple[float, float] | FloatArray:
        """(x0, y0) metres."""
        ...

    @property
    def cell_size(self) -> float:
        """Grid spacing, metres."""
        ...

    @property
    def heights(self) -> FloatArray:
        """(rows, cols) heights, metres (NaN = unknown)."""
        ...

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols)."""
        ...
