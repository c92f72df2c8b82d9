"""The ``"terrain"`` helicopter world model: random crops of a real elevation model, and the grids it reads.

The elevation model (ESRI ASCII grid at ``path``; default
:func:`~drd_planner.domains.helicopter_world_params.default_terrain_path`; any grid works, its own cell size is
ignored) is cropped at a random place, rotated by a random angle (and mirrored with probability ``mirror``),
resampled at ``metres_per_cell`` metres per source cell east-west and ``cell_aspect`` times that north-south
(compressing the real ~90 m cells so a corridor holds ridges and valleys; a geographic grid's cells are longer
north-south than east-west), scaled so its 2-98 % height range spans ``relief`` metres (``relief`` null: the grid's
own heights, not scaled), and shifted so a fraction
``open_fraction`` of it lies at least the vehicle clearance below the start altitude. Within
``keep_clear_radius`` of the start and goal it is capped ``ground_gap`` below that (a smooth pad), so both are
always clear. Windows with unknown (NODATA) heights are redrawn up to ``max_tries`` times. With ``site`` =
[row, col] (fractions of the grid) the crop is centred on that one operating area, shifted by up to
``site_jitter`` metres per axis (see :class:`~drd_planner.domains.helicopter_world_params.TerrainParams`).

:class:`TerrainModel` owns a :class:`TerrainGrids` cache, so a grid file is read once per file version.

Units: metres, degrees where the name says ``_deg``.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from pathlib import Path
from typing import Any

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.domains.helicopter_world_frame import ModelDraw, WorldFrame, draw_uniform, flatten_near
from drd_planner.domains.helicopter_world_params import DEFAULT_TERRAIN_FILE, TerrainParams
from drd_planner.exceptions import GeometryError, ProblemError
from drd_planner.geometry.geotiff import is_geotiff, read_geotiff
from drd_planner.geometry.terrain import Heightfield, read_esri_ascii

__all__ = ["TerrainGrids", "TerrainModel"]


class TerrainGrids:
    """Elevation grids read from disk, kept per file version (resolved path, modification time).

    A file ending in ``.tif`` or ``.tiff`` is read as a GeoTIFF (:mod:`~drd_planner.geometry.geotiff`: its size
    checked from the header first; whether its CRS is geographic is kept, see :meth:`units`); any other as an
    ESRI ASCII grid. At most ``size`` grids are kept; the least recently used one goes first.
    """

    def __init__(self, size: int = 4) -> None:
        if size < 1:
            raise ValueError(f"a terrain grid cache holds at least one grid, got size {size}")
        self._size = size
        self._grids: OrderedDict[tuple[str, int], Heightfield] = OrderedDict()
        self._units: dict[str, str] = {}

    def __len__(self) -> int:
        """Number of grids kept."""
        return len(self._grids)

    def units(self, path: Path) -> str | None:
        """How a loaded GeoTIFF's x and y are measured: "degrees" or "metres" (from its CRS).

        None: not known (an ESRI ASCII grid, a GeoTIFF without a CRS, or a file not loaded yet).
        """
        return self._units.get(str(path.resolve()))

    def load(self, path: Path) -> Heightfield:
        """The elevation grid at ``path``, GeoTIFF or ESRI ASCII (read once per file version).

        Raises:
            ProblemError: the file is missing or not a usable grid (the message names the path).
        """
        if not path.is_file():
            raise ProblemError(
                f"terrain elevation grid {path} not found; set the terrain model's 'path' or DRD_SHARED_DATA "
                f"(expected {DEFAULT_TERRAIN_FILE} under it)"
            )
        key = (str(path.resolve()), path.stat().st_mtime_ns)
        grid = self._grids.get(key)
        if grid is not None:
            self._grids.move_to_end(key)
            return grid
        try:
            if is_geotiff(path):
                grid, header = read_geotiff(key[0])
                if header.crs_wkt:
                    self._units[key[0]] = "degrees" if header.geographic else "metres"
            else:
                grid = read_esri_ascii(key[0])
        except GeometryError as exc:
            raise ProblemError(f"cannot use terrain grid {path}: {exc}") from exc
        self._grids[key] = grid
        if len(self._grids) > self._size:
            self._grids.popitem(last=False)
        return grid


def _bilinear_index(grid: FloatArray, fi: FloatArray, fj: FloatArray) -> FloatArray:
    """Bilinear samples of (rows, cols) ``grid`` at fractional (row, col) indices (inside the grid)."""
    rows, cols = grid.shape
    i = np.clip(np.floor(fi).astype(np.int64), 0, rows - 2)
    j = np.clip(np.floor(fj).astype(np.int64), 0, cols - 2)
    v, u = fi - i, fj - j
    return np.asarray(
        (1 - v) * ((1 - u) * grid[i, j] + u * grid[i, j + 1]) + v * ((1 - u) * grid[i + 1, j] + u * grid[i + 1, j + 1])
    )


def _crop_centre(
    rng: np.random.Generator,
    p: TerrainParams,
    shape: tuple[int, int],
    mpc: float,
    radius: tuple[float, float],
) -> tuple[float, float] | None:
    """The crop's centre (row, col) in fractional grid cells, or None when the crop leaves the grid.

    ``radius``: the crop's half diagonal in (rows, cols) of source cells; ``mpc``: metres per cell east-west.
    """
    rows, cols = shape
    radius_rows, radius_cols = radius
    if p.site is None:
        ci = rng.uniform(radius_rows, rows - 1 - radius_rows)
        cj = rng.uniform(radius_cols, cols - 1 - radius_cols)
        return ci, cj
    jitter_rows, jitter_cols = p.site_jitter / (mpc * p.cell_aspect), p.site_jitter / mpc
    ci = p.site[0] * (rows - 1) + rng.uniform(-jitter_rows, jitter_rows)
    cj = p.site[1] * (cols - 1) + rng.uniform(-jitter_cols, jitter_cols)
    inside = radius_rows <= ci <= rows - 1 - radius_rows and radius_cols <= cj <= cols - 1 - radius_cols
    return (ci, cj) if inside else None


class _Window:
    """The frame's terrain grid, centred, and what the crops need from it (metres)."""

    def __init__(self, frame: WorldFrame) -> None:
        xs, ys = frame.grid()
        self.gx, self.gy = np.meshgrid(xs, ys)
        self.centre = (0.5 * (xs[0] + xs[-1]), 0.5 * (ys[0] + ys[-1]))
        self.half_diag = 0.5 * math.hypot(xs[-1] - xs[0], ys[-1] - ys[0])
        self.keep = np.asarray(frame.keep_clear, dtype=np.float64).reshape(-1, 3)
        self.target = (float(self.keep[:, 2].min()) if self.keep.size else frame.lowest_level) - frame.clearance


def _sample_crop(
    grid: FloatArray,
    window: _Window,
    centre: tuple[float, float],
    cell: tuple[float, float],
    turn: tuple[float, bool],
) -> FloatArray:
    """Source heights on the window, rotated by ``turn`` = (theta rad, mirrored) about the crop ``centre``.

    ``cell``: (metres per cell east-west, north-south over east-west) of the source grid.
    """
    theta, flip = turn
    mpc, aspect = cell
    dx, dy = (window.gx - window.centre[0]) / mpc, (window.gy - window.centre[1]) / mpc
    if flip:
        dx = -dx
    c, s = math.cos(theta), math.sin(theta)
    return _bilinear_index(grid, centre[0] + (s * dx + c * dy) / aspect, centre[1] + c * dx - s * dy)


def _scale_and_shift(
    rng: np.random.Generator, p: TerrainParams, heights: FloatArray, window: _Window
) -> tuple[FloatArray, dict[str, Any]]:
    """Heights scaled to a drawn relief, shifted to a drawn open fraction and padded at the keep-clear points."""
    lo, hi = np.percentile(heights, [2.0, 98.0])
    if p.relief is None:  # the grid's own heights (``--crop as-is``)
        relief = float(hi - lo)
        heights = heights - lo
    else:
        relief = draw_uniform(rng, p.relief)
        heights = (heights - lo) * (relief / max(float(hi - lo), 1.0))
    open_fraction = draw_uniform(rng, p.open_fraction)
    shift = window.target - float(np.quantile(heights, open_fraction))
    heights = heights + shift
    gap = draw_uniform(rng, p.ground_gap)
    heights = flatten_near(
        heights, window.gx, window.gy, window.keep, cap=window.target - gap, radius=p.keep_clear_radius
    )
    return heights, {"relief": relief, "open_fraction": open_fraction, "ground_gap": gap, "shift": shift}


class TerrainModel:
    """The ``"terrain"`` world model; it owns the cache of the elevation grids it crops."""

    def __init__(self, grids: TerrainGrids | None = None) -> None:
        self.grids = TerrainGrids() if grids is None else grids

    def draw(self, rng: np.random.Generator, p: TerrainParams, frame: WorldFrame) -> ModelDraw:
        """A random crop, rotation, resampling and vertical scaling of the real elevation model.

        Raises:
            ProblemError: the grid is missing or unusable, or no NaN-free window was found in ``max_tries``.
        """
        path = p.resolved_path()
        grid = self.grids.load(path).heights
        rows, cols = grid.shape
        window = _Window(frame)
        for _attempt in range(p.max_tries):
            mpc = draw_uniform(rng, p.metres_per_cell)
            radius = (window.half_diag / (mpc * p.cell_aspect), window.half_diag / mpc)
            if 2.0 * radius[0] > rows - 1 or 2.0 * radius[1] > cols - 1:
                continue
            centre = _crop_centre(rng, p, (rows, cols), mpc, radius)
            if centre is None:
                continue
            theta = math.radians(draw_uniform(rng, p.rotation_deg))
            flip = bool(rng.random() < p.mirror)
            heights = _sample_crop(grid, window, centre, (mpc, p.cell_aspect), (theta, flip))
            if np.isnan(heights).any():
                continue
            heights, drawn = _scale_and_shift(rng, p, heights, window)
            info = {
                "path": str(path),
                "metres_per_cell": mpc,
                "centre_cell": [centre[0], centre[1]],
                "rotation_deg": math.degrees(theta),
                "flipped": flip,
                **drawn,
            }
            if p.cell_aspect != 1.0:
                info["cell_aspect"] = p.cell_aspect
            return ModelDraw(frame.heightfield(heights), (), (), info)
        raise ProblemError(
            f"terrain grid {path} ({rows} x {cols} cells) has no NaN-free window for a "
            f"{2 * window.half_diag:.0f} m corridor at {p.metres_per_cell} m per cell after {p.max_tries} tries; "
            "lower metres_per_cell" + ("" if p.site is None else " or move the site away from the grid's border")
        )
