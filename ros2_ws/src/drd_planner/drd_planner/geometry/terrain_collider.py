"""Terrain in the scene: FCL mesh tiles, a grid prefilter for spheres, and the below-terrain test.

The surface is the heightfield's collision surface (:attr:`Heightfield.surface_heights`: unknown heights filled as
its ``unknown`` option says, so by default a cell with an unknown corner is a wall). It is cut into square tiles of
``tile_cells`` x ``tile_cells`` cells, each its own FCL ``BVHModel``,
so a query only meets the few tiles under it. Spheres are sorted into three cases with numpy alone:

- *clear*: the sphere's bottom is above the highest grid point of every cell its footprint touches (the
  triangulated surface never rises above its corners), so it cannot touch the surface;
- *below*: its centre is under the triangulated surface (FCL would call a sphere wholly under the terrain
  free, because a mesh is a surface; the scene calls it blocked);
- otherwise the sphere goes to FCL against the tiles its footprint overlaps.
"""

from __future__ import annotations

import math

import fcl
import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from scipy.ndimage import maximum_filter1d

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.exceptions import GeometryError
from drd_planner.geometry.shapes import bvh_model
from drd_planner.geometry.terrain import Heightfield, cell_triangles

__all__ = ["TerrainCollider", "cell_maxima", "window_max"]


def cell_maxima(surface: FloatArray) -> FloatArray:
    """(rows - 1, cols - 1) highest of the four corner heights (metres) of each cell of a (rows, cols) grid.

    NaN corners are skipped; a cell with no known corner gets -inf (no surface to touch).
    """
    top = np.fmax(np.fmax(surface[:-1, :-1], surface[:-1, 1:]), np.fmax(surface[1:, :-1], surface[1:, 1:]))
    result: FloatArray = np.where(np.isnan(top), -np.inf, top)
    return result


def window_max(values: FloatArray, half: int) -> FloatArray:
    """(n, m) max of the (n, m) ``values`` over the (2 * half + 1)-square window centred on each entry.

    Entries outside the array count as -inf. Two separable 1-D passes, so the cost is linear in ``values.size``
    whatever ``half`` is (a half-width beyond the array's size is clipped: the window already covers it all).
    """
    if half < 0:
        raise GeometryError(f"window half-width must be >= 0, got {half}")
    out = values
    for axis in (0, 1):
        size = 2 * min(int(half), values.shape[axis]) + 1
        out = maximum_filter1d(out, size=size, axis=axis, mode="constant", cval=-np.inf)
    result: FloatArray = out
    return result


class TerrainCollider:
    """FCL tiles and numpy prefilters of one :class:`Heightfield`.

    Args:
        heightfield: the terrain.
        tile_cells: cells per tile side (>= 1); smaller tiles mean cheaper narrowphase but more objects.
    """

    def __init__(self, heightfield: Heightfield, *, tile_cells: int = 8) -> None:
        if int(tile_cells) != tile_cells or tile_cells < 1:
            raise GeometryError(f"tile_cells must be an integer >= 1, got {tile_cells!r}")
        self._field = heightfield
        self._tile = int(tile_cells)
        raw = ~np.isnan(heightfield.heights)
        if not (raw[:-1, :-1] & raw[:-1, 1:] & raw[1:, :-1] & raw[1:, 1:]).any():
            raise GeometryError(f"{heightfield!r} has no cell with four known corners")
        heights = heightfield.surface_heights
        # Highest corner of each cell of the collision surface (no unknown corner is left in it).
        self._cell_max = cell_maxima(heights)
        self._window_max: dict[int, FloatArray] = {}
        self._objects: list[fcl.CollisionObject] = []
        lo_list: list[FloatArray] = []
        hi_list: list[FloatArray] = []
        rows, cols = heightfield.shape
        n_ti = math.ceil((rows - 1) / self._tile)
        n_tj = math.ceil((cols - 1) / self._tile)
        self._tile_id = np.full((n_ti, n_tj), -1, dtype=np.int64)
        size = heightfield.cell_size
        xs = heightfield.origin[0] + size * np.arange(cols)
        ys = heightfield.origin[1] + size * np.arange(rows)
        for ti in range(n_ti):
            for tj in range(n_tj):
                i0, j0 = ti * self._tile, tj * self._tile
                i1, j1 = min(i0 + self._tile, rows - 1), min(j0 + self._tile, cols - 1)
                block = heights[i0 : i1 + 1, j0 : j1 + 1]
                faces = cell_triangles(block)
                if faces.shape[0] == 0:
                    continue
                gx, gy = np.meshgrid(xs[j0 : j1 + 1], ys[i0 : i1 + 1])
                verts = np.stack([gx.ravel(), gy.ravel(), np.nan_to_num(block, nan=0.0).ravel()], axis=1)
                used = verts[np.unique(faces)]
                self._tile_id[ti, tj] = len(self._objects)
                self._objects.append(fcl.CollisionObject(bvh_model(verts, faces), fcl.Transform()))
                lo_list.append(used.min(axis=0))
                hi_list.append(used.max(axis=0))
        if not self._objects:
            raise GeometryError(f"{heightfield!r} has no cell with four known corners")
        self._lo = np.array(lo_list)
        self._hi = np.array(hi_list)

    @property
    def heightfield(self) -> Heightfield:
        """The terrain."""
        return self._field

    @property
    def objects(self) -> list[fcl.CollisionObject]:
        """The FCL tile objects (world frame), in tile-id order."""
        return list(self._objects)

    @property
    def tile_boxes(self) -> tuple[FloatArray, FloatArray]:
        """``(lo, hi)``, each (T, 3) in metres: the AABB of every tile, in tile-id order."""
        return self._lo, self._hi

    @property
    def bounds(self) -> tuple[FloatArray, FloatArray]:
        """``(lo, hi)``, each (3,) in metres: the AABB of the whole surface."""
        return self._lo.min(axis=0), self._hi.max(axis=0)

    def below(self, centres: FloatArray) -> BoolArray:
        """(K,) bool: which of the (K, 3) points lie under the triangulated collision surface."""
        return self._field.below(centres, interpolation="triangles")

    def classify(self, centres: FloatArray, radii: FloatArray) -> tuple[BoolArray, IntArray, IntArray]:
        """Below-terrain spheres and the sphere/tile pairs that FCL must decide.

        Args:
            centres: (K, 3) sphere centres in metres.
            radii: (K,) sphere radii in metres (already including any margin).

        Returns:
            ``(below, spheres, tiles)``: (K,) bool, True where the centre is under the triangulated surface
            (wholly-under spheres are caught here, since FCL sees only the surface); and two (P,) int64 arrays of
            sphere indices and tile ids (indices into :attr:`objects`) for the remaining spheres that reach
            below the highest terrain under their footprint.
        """
        below = np.zeros(centres.shape[0], dtype=bool)
        field = self._field
        rows, cols = field.shape
        size = field.cell_size
        fx = (centres[:, 0] - field.origin[0]) / size
        fy = (centres[:, 1] - field.origin[1]) / size
        span = radii / size
        j0 = np.floor(fx - span).astype(np.int64)
        j1 = np.floor(fx + span).astype(np.int64)
        i0 = np.floor(fy - span).astype(np.int64)
        i1 = np.floor(fy + span).astype(np.int64)
        near = (j1 >= 0) & (j0 < cols - 1) & (i1 >= 0) & (i0 < rows - 1)
        if not near.any():
            return below, _EMPTY, _EMPTY
        for index, last in ((j0, cols - 2), (j1, cols - 2), (i0, rows - 2), (i1, rows - 2)):
            np.maximum(index, 0, out=index)
            np.minimum(index, last, out=index)
        width = int(max((j1 - j0).max(), (i1 - i0).max())) + 1
        top = self._window(width)[i0, j0] if width <= _MAX_WINDOW else np.full(len(i0), self._hi[:, 2].max())
        band = np.nonzero(near & (centres[:, 2] - radii <= top))[0]
        if band.size == 0:
            return below, _EMPTY, _EMPTY
        below[band] = field.below(centres[band], interpolation="triangles")
        spheres: list[int] = []
        tiles: list[int] = []
        tile = self._tile
        for k in band[~below[band]].tolist():
            ids = self._tile_id[i0[k] // tile : i1[k] // tile + 1, j0[k] // tile : j1[k] // tile + 1]
            for tid in ids[ids >= 0].tolist():
                spheres.append(k)
                tiles.append(tid)
        if not spheres:
            return below, _EMPTY, _EMPTY
        ks = np.array(spheres, dtype=np.int64)
        ts = np.array(tiles, dtype=np.int64)
        keep = np.all(
            (centres[ks] - radii[ks, None] <= self._hi[ts]) & (centres[ks] + radii[ks, None] >= self._lo[ts]),
            axis=1,
        )
        return below, ks[keep], ts[keep]

    def _window(self, width: int) -> FloatArray:
        """(n_i, n_j) max of the cell maxima over the ``width`` x ``width`` cell block starting at each cell."""
        cached = self._window_max.get(width)
        if cached is None:
            padded = np.pad(self._cell_max, ((0, width - 1), (0, width - 1)), constant_values=-np.inf)
            cached = sliding_window_view(padded, (width, width)).max(axis=(-2, -1))
            self._window_max[width] = cached
        return cached


_EMPTY = np.zeros(0, dtype=np.int64)
#: Widest footprint (in cells) served by a cached sliding-window maximum; wider ones use the global maximum.
_MAX_WINDOW = 16
