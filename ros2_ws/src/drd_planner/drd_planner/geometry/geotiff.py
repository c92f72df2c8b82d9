"""GeoTIFF elevation models: the header looked at first (size, georeferencing, CRS), then the heights.

:func:`read_geotiff_header` opens the file with rasterio and reads only its header; a raster of more than
``max_cells`` cells (width x height x bands) is refused before any pixel is read, so a small file that
declares a billion cells costs nothing. :func:`read_geotiff` then reads band 1 into a
:class:`~drd_planner.geometry.terrain.Heightfield` (rows south to north, grid point [0, 0] the centre of the
lower-left pixel, NODATA as NaN); :func:`write_geotiff` writes one (float32, deflate-compressed, NODATA -9999),
e.g. a crop (:func:`crop_heightfield`) of an ESRI ASCII grid. Only north-up rasters with square pixels are read
(no rotation or shear terms); the CRS is reported, not changed: a geographic raster has its cell size in degrees.

Units: the raster's own (degrees or metres horizontally, its height unit vertically).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drd_planner.exceptions import GeometryError
from drd_planner.geometry.terrain import Heightfield

__all__ = [
    "GEOTIFF_SUFFIXES",
    "MAX_DEM_CELLS",
    "GeoTiffHeader",
    "crop_heightfield",
    "is_geotiff",
    "read_geotiff",
    "read_geotiff_header",
    "write_geotiff",
]

#: File name endings read as GeoTIFF (lower case).
GEOTIFF_SUFFIXES: tuple[str, ...] = (".tif", ".tiff")

#: Most cells (width x height x bands) of an elevation raster that is read (50 million: a 7000 x 7000 tile).
MAX_DEM_CELLS = 50_000_000


def is_geotiff(path: str | Path) -> bool:
    """Whether ``path`` names a GeoTIFF (by its ending, see :data:`GEOTIFF_SUFFIXES`)."""
    return Path(path).suffix.lower() in GEOTIFF_SUFFIXES


@dataclass(frozen=True)
class GeoTiffHeader:
    """What a GeoTIFF's header says.

    Attributes:
        path: the file.
        width: columns (count).
        height: rows (count).
        bands: bands (count); band 1 holds the heights.
        transform: (a, b, c, d, e, f) affine map from (col, row) pixel corners to x, y: x = a col + b row + c,
            y = d col + e row + f (the raster's units).
        crs_wkt: its coordinate reference system as WKT; "" when it has none.
        geographic: whether the CRS is geographic (x longitude, y latitude in degrees).
        nodata: the NODATA value of band 1, or None.
    """

    path: str
    width: int
    height: int
    bands: int
    transform: tuple[float, float, float, float, float, float]
    crs_wkt: str
    geographic: bool
    nodata: float | None

    @property
    def cell(self) -> float:
        """Pixel width in the raster's x unit."""
        return abs(self.transform[0])

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(x0, x1, y0, y1): the outer edges of the raster (north-up)."""
        a, _b, c, _d, e, f = self.transform
        xs = (c, c + a * self.width)
        ys = (f, f + e * self.height)
        return min(xs), max(xs), min(ys), max(ys)


def read_geotiff_header(path: str | Path, *, max_cells: int = MAX_DEM_CELLS) -> GeoTiffHeader:
    """The header of the GeoTIFF at ``path``; no pixel is read.

    Raises:
        GeometryError: not a readable GeoTIFF, more than ``max_cells`` cells (width x height x bands), a
            rotated or sheared raster, or pixels that are not square.
    """
    import rasterio
    from rasterio.errors import RasterioError

    file = Path(path)
    try:
        with rasterio.open(file) as src:
            width, height, bands = int(src.width), int(src.height), int(src.count)
            t = src.transform
            transform = (float(t.a), float(t.b), float(t.c), float(t.d), float(t.e), float(t.f))
            crs = src.crs
            crs_wkt = crs.to_wkt() if crs is not None else ""
            geographic = bool(crs is not None and crs.is_geographic)
            nodata = None if src.nodata is None else float(src.nodata)
    except (RasterioError, OSError) as exc:
        raise GeometryError(f"cannot read GeoTIFF {file}: {exc}") from None
    cells = width * height * max(bands, 1)
    if cells > max_cells:
        raise GeometryError(
            f"GeoTIFF {file} declares {width} x {height} x {bands} = {cells} cells; at most {max_cells} are read "
            "(crop the DEM to the site first)"
        )
    if width < 2 or height < 2 or bands < 1:
        raise GeometryError(f"GeoTIFF {file} must have at least 2 x 2 pixels and one band, got {width} x {height}")
    a, b, _c, d, e, _f = transform
    if b != 0.0 or d != 0.0 or not all(math.isfinite(v) for v in transform):
        raise GeometryError(f"GeoTIFF {file} is rotated or sheared (transform {transform}); only north-up rasters")
    if a <= 0.0 or e == 0.0 or not math.isclose(abs(a), abs(e), rel_tol=1e-6):
        raise GeometryError(f"GeoTIFF {file} pixels must be square, got {a:g} x {abs(e):g}; resample it first")
    return GeoTiffHeader(str(file), width, height, bands, transform, crs_wkt, geographic, nodata)


def read_geotiff(path: str | Path, *, max_cells: int = MAX_DEM_CELLS) -> tuple[Heightfield, GeoTiffHeader]:
    """Band 1 of the GeoTIFF at ``path`` as a heightfield (after :func:`read_geotiff_header`'s checks).

    Returns:
        The heightfield ((rows, cols) heights, row 0 the southernmost, NODATA and non-finite as NaN; origin
        the centre of the lower-left pixel; cell size the pixel size in the raster's units) and the header.

    Raises:
        GeometryError: see :func:`read_geotiff_header`, or unreadable pixels.
    """
    import rasterio
    from rasterio.errors import RasterioError

    header = read_geotiff_header(path, max_cells=max_cells)
    try:
        with rasterio.open(header.path) as src:
            data = np.asarray(src.read(1), dtype=np.float64)
    except (RasterioError, OSError) as exc:
        raise GeometryError(f"cannot read the pixels of GeoTIFF {header.path}: {exc}") from None
    if header.nodata is not None:
        data = np.where(data == header.nodata, np.nan, data)
    data = np.where(np.isfinite(data), data, np.nan)
    a, _b, c, _d, e, f = header.transform
    if e < 0.0:  # row 0 is the northernmost: flip so that row 0 is the southernmost
        data = data[::-1]
        y0 = f + e * header.height - e / 2.0
    else:
        y0 = f + e / 2.0
    origin = (c + a / 2.0, y0)
    return Heightfield(origin, a, data), header


#: NODATA value of the GeoTIFFs :func:`write_geotiff` writes.
WRITE_NODATA = -9999.0


def crop_heightfield(grid: Heightfield, x_range: tuple[float, float], y_range: tuple[float, float]) -> Heightfield:
    """The grid points of ``grid`` with x in ``x_range`` and y in ``y_range`` (the grid's units).

    Raises:
        GeometryError: fewer than 2 x 2 points inside.
    """
    rows, cols = grid.heights.shape
    xs = grid.origin[0] + grid.cell_size * np.arange(cols)
    ys = grid.origin[1] + grid.cell_size * np.arange(rows)
    keep_x = np.flatnonzero((xs >= x_range[0]) & (xs <= x_range[1]))
    keep_y = np.flatnonzero((ys >= y_range[0]) & (ys <= y_range[1]))
    if keep_x.size < 2 or keep_y.size < 2:
        raise GeometryError(
            f"the crop x {x_range}, y {y_range} holds {keep_x.size} x {keep_y.size} grid points; the grid spans "
            f"x [{xs[0]:g}, {xs[-1]:g}], y [{ys[0]:g}, {ys[-1]:g}]"
        )
    heights = grid.heights[keep_y[0] : keep_y[-1] + 1, keep_x[0] : keep_x[-1] + 1]
    return Heightfield((xs[keep_x[0]], ys[keep_y[0]]), grid.cell_size, heights)


def write_geotiff(path: str | Path, grid: Heightfield, crs: str) -> None:
    """Write ``grid`` as a north-up single-band float32 GeoTIFF in ``crs`` (e.g. "EPSG:4326").

    NaN heights are written as NODATA (:data:`WRITE_NODATA`).

    Raises:
        GeometryError: rasterio cannot write the file or does not know ``crs``.
    """
    import rasterio
    from rasterio.errors import RasterioError
    from rasterio.transform import Affine

    rows, cols = grid.heights.shape
    cell = float(grid.cell_size)
    west = float(grid.origin[0]) - cell / 2.0
    north = float(grid.origin[1]) + (rows - 0.5) * cell
    data = np.where(np.isnan(grid.heights), WRITE_NODATA, grid.heights)[::-1].astype(np.float32)
    try:
        with rasterio.open(
            Path(path),
            "w",
            driver="GTiff",
            width=cols,
            height=rows,
            count=1,
            dtype="float32",
            crs=crs,
            transform=Affine(cell, 0.0, west, 0.0, -cell, north),
            nodata=WRITE_NODATA,
            compress="deflate",
        ) as dst:
            dst.write(data, 1)
    except (RasterioError, OSError) as exc:
        raise GeometryError(f"cannot write GeoTIFF {path}: {exc}") from None
