"""Terrain as a regular height grid: lookup, cropping, meshing and the ESRI ASCII grid reader.

Grid convention: ``heights[i, j]`` is the terrain height (metres) at the grid point
``(x, y) = (origin_x + j * cell_size, origin_y + i * cell_size)``; row 0 is the southernmost row (smallest y),
unlike the ESRI file, which lists rows north to south. NaN means unknown. Between grid points the surface is
either bilinear (``interpolation="bilinear"``, the default) or the two-triangle split of each cell along its
(i, j)-(i+1, j+1) diagonal (``interpolation="triangles"``), which is exactly the surface of :meth:`to_mesh`.
Points outside the grid have unknown (NaN) height.

Unknown heights in collision checks: the scene collides against :attr:`Heightfield.surface_heights`, the grid
with every unknown point filled as the heightfield's ``unknown`` option says:

- ``"blocked"`` (the default, the safe choice): an unknown point stands :data:`BLOCKED_HEIGHT` metres above the
  highest known one, so every cell with an unknown corner is a wall no vehicle passes over;
- ``"highest_neighbour"``: every 8-connected region of unknown points takes the height of the highest known
  grid point next to it (a gap in a plateau is plateau, a gap in a valley is at the valley's rim).

Outside the grid there is no terrain (nothing is below it), whatever the option.

The shared elevation model ``data/terrain/srtm_front_range_144.asc`` (144 x 144 points) has a geographic
header: ``cellsize 0.000833333333`` arc-degrees (3 arc-seconds), i.e. about 92.6 m north-south and about 71 m
east-west at its latitude (40.09 deg N). A metric planner should use ``read_esri_ascii(path).with_cell_size(90.0)``
(the usual "90 m SRTM" square-cell approximation) or compute the spacing with :func:`arc_degrees_to_metres`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
import numpy.typing as npt
from scipy import ndimage

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.exceptions import GeometryError
from drd_planner.geometry.pose import as_points
from drd_planner.geometry.shapes import TriangleMesh

Interpolation = Literal["bilinear", "triangles"]
#: How unknown (NaN) heights count in collision checks (see the module docstring).
Unknown = Literal["blocked", "highest_neighbour"]
UNKNOWN_CHOICES: tuple[str, ...] = ("blocked", "highest_neighbour")

__all__ = [
    "BLOCKED_HEIGHT",
    "UNKNOWN_CHOICES",
    "Heightfield",
    "Interpolation",
    "Unknown",
    "arc_degrees_to_metres",
    "read_esri_ascii",
]

#: Metres per degree of latitude (mean; WGS84 varies by < 0.6 %).
METRES_PER_DEGREE = 111_320.0
#: Metres above the highest known height at which ``unknown="blocked"`` puts unknown grid points.
BLOCKED_HEIGHT = 1e6


@dataclass(frozen=True, eq=False, init=False, repr=False)
class Heightfield:
    """A regular grid of terrain heights.

    Attributes:
        origin: (2,) x, y in metres of grid point [0, 0] (the centre of the ESRI lower-left cell).
        cell_size: spacing of grid points in metres along x and y (finite, > 0).
        heights: (rows, cols) float64 heights in metres, rows >= 2 and cols >= 2; row i at
            y = origin_y + i * cell_size, column j at x = origin_x + j * cell_size; NaN = unknown.
        unknown: how unknown heights count in collision checks, ``"blocked"`` (default) or
            ``"highest_neighbour"`` (see :attr:`surface_heights`).
    """

    origin: FloatArray
    cell_size: float
    heights: FloatArray
    unknown: Unknown

    def __init__(
        self, origin: npt.ArrayLike, cell_size: float, heights: npt.ArrayLike, *, unknown: Unknown = "blocked"
    ) -> None:
        if unknown not in UNKNOWN_CHOICES:
            raise GeometryError(
                f"unknown terrain must be one of {', '.join(map(repr, UNKNOWN_CHOICES))}, got {unknown!r}"
            )
        try:
            grid = np.array(heights, dtype=np.float64)
            origin_xy = np.array(origin, dtype=np.float64)
            size = float(cell_size)
        except (TypeError, ValueError) as exc:
            raise GeometryError(f"heightfield origin, cell size and heights must be numeric: {exc}") from exc
        if origin_xy.shape != (2,) or not np.all(np.isfinite(origin_xy)):
            raise GeometryError(f"heightfield origin must be two finite numbers, got {origin_xy.tolist()}")
        if not math.isfinite(size) or size <= 0.0:
            raise GeometryError(f"heightfield cell size must be finite and > 0, got {cell_size!r}")
        if grid.ndim != 2 or grid.shape[0] < 2 or grid.shape[1] < 2:
            raise GeometryError(f"heightfield heights must have shape (rows >= 2, cols >= 2), got {grid.shape}")
        if np.any(np.isinf(grid)):
            raise GeometryError("heightfield heights must be finite or NaN (unknown), not infinite")
        grid.flags.writeable = False
        origin_xy.flags.writeable = False
        object.__setattr__(self, "origin", origin_xy)
        object.__setattr__(self, "cell_size", size)
        object.__setattr__(self, "heights", grid)
        object.__setattr__(self, "unknown", unknown)
        object.__setattr__(self, "_surface", None)

    def __repr__(self) -> str:
        rows, cols = self.heights.shape
        return f"Heightfield({rows}x{cols}, origin={self.origin.tolist()}, cell_size={self.cell_size})"

    @property
    def surface_heights(self) -> FloatArray:
        """(rows, cols) float64 heights in metres that collision checks use: :attr:`heights` with unknowns filled.

        ``unknown="blocked"``: an unknown point is :data:`BLOCKED_HEIGHT` above the highest known height;
        ``"highest_neighbour"``: each 8-connected unknown region is at the highest known height next to it.
        With no unknown point this is :attr:`heights` itself; with no known point at all it stays NaN.
        Computed once (linear in the number of grid points).
        """
        surface: FloatArray | None = self.__dict__.get("_surface")
        if surface is None:
            surface = _fill_unknown(self.heights, self.unknown)
            object.__setattr__(self, "_surface", surface)
        return surface

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols) of the grid."""
        rows, cols = self.heights.shape
        return int(rows), int(cols)

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(x_min, x_max, y_min, y_max) in metres: the rectangle spanned by the grid points."""
        rows, cols = self.shape
        x0, y0 = float(self.origin[0]), float(self.origin[1])
        return x0, x0 + (cols - 1) * self.cell_size, y0, y0 + (rows - 1) * self.cell_size

    def with_cell_size(self, cell_size: float, *, origin: npt.ArrayLike | None = None) -> Heightfield:
        """The same heights on a grid of spacing ``cell_size`` metres (e.g. to turn arc-degrees into metres).

        Args:
            cell_size: new grid spacing in metres.
            origin: (2,) new position of grid point [0, 0] in metres; default (0, 0), since an origin given in
                degrees means nothing in a metric frame.
        """
        return Heightfield((0.0, 0.0) if origin is None else origin, cell_size, self.heights, unknown=self.unknown)

    def height_at(self, xy: npt.ArrayLike, *, interpolation: Interpolation = "bilinear") -> FloatArray:
        """(K,) terrain heights in metres at (K, 2) points ``xy`` (metres); NaN outside the grid or unknown.

        A single (2,) point gives a (1,) array. ``interpolation`` is ``"bilinear"`` or ``"triangles"``
        (the surface of :meth:`to_mesh`); both agree at grid points. These are the measured heights; collision
        checks use :meth:`surface_at` (unknowns filled).
        """
        return self._interpolate(self.heights, xy, interpolation)

    def surface_at(self, xy: npt.ArrayLike, *, interpolation: Interpolation = "bilinear") -> FloatArray:
        """(K,) heights in metres of the collision surface (:attr:`surface_heights`) at (K, 2) points ``xy``.

        NaN outside the grid (and nowhere inside unless no height at all is known).
        """
        return self._interpolate(self.surface_heights, xy, interpolation)

    def _interpolate(self, grid: FloatArray, xy: npt.ArrayLike, interpolation: Interpolation) -> FloatArray:
        """(K,) values of the (rows, cols) ``grid`` at (K, 2) points ``xy`` (NaN outside the grid)."""
        points = _as_xy(xy)
        rows, cols = self.shape
        fx = (points[:, 0] - self.origin[0]) / self.cell_size
        fy = (points[:, 1] - self.origin[1]) / self.cell_size
        inside = (fx >= 0.0) & (fx <= cols - 1) & (fy >= 0.0) & (fy <= rows - 1)
        j = np.clip(np.floor(fx), 0, cols - 2).astype(np.int64)
        i = np.clip(np.floor(fy), 0, rows - 2).astype(np.int64)
        u = fx - j
        v = fy - i
        h = grid
        h00, h10, h01, h11 = h[i, j], h[i, j + 1], h[i + 1, j], h[i + 1, j + 1]
        if interpolation == "bilinear":
            out = (1 - v) * ((1 - u) * h00 + u * h10) + v * ((1 - u) * h01 + u * h11)
        elif interpolation == "triangles":
            lower = u >= v  # triangle (0,0)-(1,0)-(1,1) versus (0,0)-(0,1)-(1,1)
            out = np.where(lower, h00 + u * (h10 - h00) + v * (h11 - h10), h00 + v * (h01 - h00) + u * (h11 - h01))
        else:
            raise GeometryError(f"interpolation must be 'bilinear' or 'triangles', got {interpolation!r}")
        result: FloatArray = np.where(inside, out, np.nan)
        return result

    def below(
        self, points: npt.ArrayLike, clearance: float = 0.0, *, interpolation: Interpolation = "bilinear"
    ) -> BoolArray:
        """(K,) bool: whether each of the (K, 3) ``points`` has z < collision surface height + ``clearance`` (m).

        The collision surface is :attr:`surface_heights` (unknown heights filled as ``unknown`` says, so under
        the default ``"blocked"`` every point over a cell with an unknown corner is below). Points outside the
        grid are not below.
        """
        array = as_points(points)
        height = self.surface_at(array[:, :2], interpolation=interpolation)
        known = ~np.isnan(height)
        result: BoolArray = known & (array[:, 2] < np.where(known, height, 0.0) + clearance)
        return result

    def crop(self, *, x_range: tuple[float, float], y_range: tuple[float, float]) -> Heightfield:
        """The sub-grid of the grid points with x in ``x_range`` and y in ``y_range`` (metres, inclusive).

        Raises:
            GeometryError: fewer than 2 x 2 grid points fall in the window.
        """
        rows, cols = self.shape
        xs = self.origin[0] + self.cell_size * np.arange(cols)
        ys = self.origin[1] + self.cell_size * np.arange(rows)
        tol = 1e-9 * self.cell_size
        jj = np.nonzero((xs >= x_range[0] - tol) & (xs <= x_range[1] + tol))[0]
        ii = np.nonzero((ys >= y_range[0] - tol) & (ys <= y_range[1] + tol))[0]
        if jj.size < 2 or ii.size < 2:
            raise GeometryError(f"crop x {x_range}, y {y_range} keeps fewer than 2 x 2 grid points of {self!r}")
        sub = self.heights[ii[0] : ii[-1] + 1, jj[0] : jj[-1] + 1]
        return Heightfield((xs[jj[0]], ys[ii[0]]), self.cell_size, sub, unknown=self.unknown)

    def grid_points(self) -> FloatArray:
        """(rows, cols, 3) world coordinates (metres) of every grid point (z NaN where unknown)."""
        rows, cols = self.shape
        xs = self.origin[0] + self.cell_size * np.arange(cols)
        ys = self.origin[1] + self.cell_size * np.arange(rows)
        gx, gy = np.meshgrid(xs, ys)
        points: FloatArray = np.stack([gx, gy, self.heights], axis=-1)
        return points

    def to_mesh(self) -> TriangleMesh:
        """The terrain surface as a triangle mesh: two triangles per cell with four known corners.

        Vertices are the (rows * cols) grid points in row-major order (unknown heights become 0 and are used
        by no triangle); each cell (i, j) is split along its (i, j)-(i+1, j+1) diagonal.

        Raises:
            GeometryError: no cell has four known corners.
        """
        faces = cell_triangles(self.heights)
        if faces.shape[0] == 0:
            raise GeometryError(f"{self!r} has no cell with four known corners")
        vertices = np.nan_to_num(self.grid_points().reshape(-1, 3), nan=0.0)
        return TriangleMesh(vertices, faces)


def cell_triangles(heights: FloatArray) -> IntArray:
    """(F, 3) vertex indices of the triangles of (rows, cols) ``heights``.

    Vertices are numbered row-major. Every cell whose four corners are known gives two triangles, split along
    its (i, j)-(i+1, j+1) diagonal, counter-clockwise seen from above.
    """
    rows, cols = heights.shape
    index = np.arange(rows * cols, dtype=np.int64).reshape(rows, cols)
    a = index[:-1, :-1]  # (i, j)
    b = index[:-1, 1:]  # (i, j+1)
    c = index[1:, :-1]  # (i+1, j)
    d = index[1:, 1:]  # (i+1, j+1)
    known = ~np.isnan(heights)
    ok = (known[:-1, :-1] & known[:-1, 1:] & known[1:, :-1] & known[1:, 1:]).ravel()
    lower = np.stack([a, b, d], axis=-1).reshape(-1, 3)[ok]
    upper = np.stack([a, d, c], axis=-1).reshape(-1, 3)[ok]
    faces: IntArray = np.stack([lower, upper], axis=1).reshape(-1, 3)
    return faces


def _fill_unknown(heights: FloatArray, unknown: Unknown) -> FloatArray:
    """(rows, cols) ``heights`` (metres, NaN = unknown) with every unknown point filled as ``unknown`` says.

    Returns ``heights`` itself when nothing is unknown or nothing is known. Linear in the number of points.
    """
    missing = np.isnan(heights)
    if not missing.any() or missing.all():
        return heights
    if unknown == "blocked":
        top = float(np.nanmax(heights)) + BLOCKED_HEIGHT
        filled: FloatArray = np.where(missing, top, heights)
    else:
        eight = np.ones((3, 3), dtype=bool)
        labels, count = ndimage.label(missing, structure=eight)
        # Highest known height among each point's 8 neighbours (-inf where none is known).
        rim = ndimage.maximum_filter(
            np.where(missing, -np.inf, heights), footprint=eight, mode="constant", cval=-np.inf
        )
        region_top = np.asarray(ndimage.maximum(rim, labels, np.arange(1, count + 1)), dtype=np.float64)
        filled = heights.copy()
        filled[missing] = region_top[labels[missing] - 1]
    filled.flags.writeable = False
    return filled


def arc_degrees_to_metres(cell_size_degrees: float, *, latitude_degrees: float) -> tuple[float, float]:
    """(east-west, north-south) metres spanned by a geographic cell of ``cell_size_degrees`` at a latitude.

    Spherical-earth approximation (111.32 km per degree of latitude); the east-west span shrinks with
    cos(latitude).
    """
    north_south = cell_size_degrees * METRES_PER_DEGREE
    return north_south * math.cos(math.radians(latitude_degrees)), north_south


_HEADER_KEYS = {
    "ncols",
    "nrows",
    "xllcorner",
    "xllcenter",
    "yllcorner",
    "yllcenter",
    "cellsize",
    "nodata_value",
}


def read_esri_ascii(path: str | Path) -> Heightfield:
    """Read an ESRI ASCII grid (``.asc``) into a :class:`Heightfield`.

    The header has ``ncols``, ``nrows``, ``xllcorner`` or ``xllcenter``, ``yllcorner`` or ``yllcenter``,
    ``cellsize`` and optionally ``NODATA_value`` (keys in any case and order); values follow, rows north to
    south, in any line layout. ``*llcorner`` is the outer corner of the lower-left cell, so grid point [0, 0]
    lies half a cell inside it; ``*llcenter`` is that point itself. NODATA values become NaN. Units are the
    file's: a geographic file gives a cell size in degrees (see :meth:`Heightfield.with_cell_size`).

    Raises:
        GeometryError: unreadable file, missing or malformed header, or the wrong number of values.
    """
    file = Path(path)
    try:
        lines = file.read_text(encoding="ascii").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise GeometryError(f"cannot read ESRI ASCII grid {file}: {exc}") from exc
    header, first_data = _read_esri_header(file, lines)
    origin = _esri_origin(file, header)
    rows, cols = int(header["nrows"]), int(header["ncols"])
    if rows != header["nrows"] or cols != header["ncols"] or rows < 2 or cols < 2:
        raise GeometryError(f"{file}: nrows and ncols must be integers >= 2, got {header['nrows']}, {header['ncols']}")
    try:
        values = np.array(" ".join(lines[first_data:]).split(), dtype=np.float64)
    except ValueError as exc:
        raise GeometryError(f"{file}: grid values must be numbers: {exc}") from exc
    if values.size != rows * cols:
        raise GeometryError(f"{file}: expected nrows * ncols = {rows * cols} values, found {values.size}")
    grid = values.reshape(rows, cols)[::-1]
    if "nodata_value" in header:
        grid = np.where(grid == header["nodata_value"], np.nan, grid)
    return Heightfield(origin, header["cellsize"], grid)


def _read_esri_header(file: Path, lines: list[str]) -> tuple[dict[str, float], int]:
    """The header of an ESRI ASCII grid's ``lines`` (keys lower-cased) and the index of its first data line.

    The header ends at the first non-blank line that does not start with a letter.

    Raises:
        GeometryError: an unknown or malformed header line, or a missing ``ncols``, ``nrows`` or ``cellsize``.
    """
    header: dict[str, float] = {}
    first_data = len(lines)
    for number, line in enumerate(lines):
        tokens = line.split()
        if not tokens:
            continue
        key = tokens[0].lower()
        if not key[0].isalpha():
            first_data = number
            break
        if key not in _HEADER_KEYS or len(tokens) != 2:
            raise GeometryError(f"{file}:{number + 1}: unexpected header line {line.strip()!r}")
        try:
            header[key] = float(tokens[1])
        except ValueError as exc:
            raise GeometryError(f"{file}:{number + 1}: header value is not a number: {line.strip()!r}") from exc
    for required in ("ncols", "nrows", "cellsize"):
        if required not in header:
            raise GeometryError(f"{file}: ESRI ASCII header lacks {required}")
    return header, first_data


def _esri_origin(file: Path, header: dict[str, float]) -> list[float]:
    """``[x, y]`` of grid point [0, 0] from the header's ``*llcorner`` (half a cell out) or ``*llcenter``.

    Raises:
        GeometryError: an axis has both or neither of its corner and centre keys.
    """
    origin: list[float] = []
    for axis in ("x", "y"):
        corner, centre = header.get(f"{axis}llcorner"), header.get(f"{axis}llcenter")
        if (corner is None) == (centre is None):
            raise GeometryError(f"{file}: ESRI ASCII header needs exactly one of {axis}llcorner, {axis}llcenter")
        origin.append(corner + header["cellsize"] / 2.0 if corner is not None else float(centre or 0.0))
    return origin


def _as_xy(xy: npt.ArrayLike) -> FloatArray:
    """``xy`` as a finite float64 (K, 2) array ((2,) becomes (1, 2))."""
    try:
        array = np.asarray(xy, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise GeometryError(f"xy must be a numeric (K, 2) array: {exc}") from exc
    if array.shape == (2,):
        array = array.reshape(1, 2)
    if array.ndim != 2 or array.shape[1] != 2:
        raise GeometryError(f"xy must have shape (K, 2), got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise GeometryError("xy must be finite")
    return array
