"""A site's elevation model (DEM): its header checked, its CRS settled, and whether it covers the lattice.

A DEM is a GeoTIFF (``.tif``/``.tiff``, read with rasterio; :mod:`~drd_planner.geometry.geotiff`) or an ESRI
ASCII grid (any other ending). Only headers are read here, so a file that is too large is refused before
its cells are: a GeoTIFF's width x height x bands, an ASCII grid's bytes and ``nrows`` x ``ncols``, each at most
:data:`~drd_planner.geometry.geotiff.MAX_DEM_CELLS` cells.

The CRS: a GeoTIFF's own (a ``crs`` given in the site file must then name the same one); an ASCII grid has
none, so it is the site file's ``crs``, or WGS84 longitude/latitude when its cell size is below 0.01 (degrees)
and its extent lies within longitudes and latitudes.

:func:`check_covers` refuses a DEM that does not hold the lattice's terrain around the origin (a tile
elsewhere on the globe, or the wrong CRS), saying where the tile is and where the origin is;
:func:`check_known_heights` then reads the DEM (its size already bounded) and refuses NODATA cells under the
lattice.

Units: the DEM's own (degrees or metres); metres in the lattice frame.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from drd_planner.data.geo_frame import WGS84, SiteFrame, crs_of
from drd_planner.exceptions import GeometryError, SiteFileError
from drd_planner.geometry.geotiff import MAX_DEM_CELLS, is_geotiff, read_geotiff, read_geotiff_header
from drd_planner.geometry.terrain import read_esri_ascii

__all__ = ["DEM_KINDS", "MAX_ASCII_DEM_BYTES", "SiteDem", "check_covers", "check_known_heights", "open_dem"]

#: DEM file kinds.
DEM_KINDS: tuple[str, ...] = ("geotiff", "esri_ascii")

#: Largest ESRI ASCII DEM read, bytes (512 MiB; its cells are bounded by :data:`MAX_DEM_CELLS` as well).
MAX_ASCII_DEM_BYTES = 512 << 20

#: Header bytes of an ESRI ASCII grid looked at (its six header lines fit many times over).
_ASCII_HEADER_BYTES = 4096

#: Header keys of an ESRI ASCII grid (lower case).
_ASCII_KEYS = ("ncols", "nrows", "xllcorner", "xllcenter", "yllcorner", "yllcenter", "cellsize", "nodata_value")

#: Below this cell size an ASCII grid without a CRS is taken to be in degrees.
_GEOGRAPHIC_CELL = 0.01


@dataclass(frozen=True)
class SiteDem:
    """A DEM's header facts.

    Attributes:
        path: the file (absolute).
        kind: one of :data:`DEM_KINDS`.
        crs: the CRS as a string pyproj reads (WKT, or the site file's text).
        geographic: whether x, y are longitude, latitude in degrees.
        bounds: (x0, x1, y0, y1) outer edges of the grid in its CRS.
        cell: cell size in its CRS's unit.
        shape: (rows, cols).
    """

    path: str
    kind: str
    crs: str
    geographic: bool
    bounds: tuple[float, float, float, float]
    cell: float
    shape: tuple[int, int]

    @property
    def units(self) -> str:
        """How x and y are measured, "degrees" or "metres" (the corridors model's ``grid_units``)."""
        return "degrees" if self.geographic else "metres"


def _ascii_header(path: Path) -> dict[str, float]:
    """The header of the ESRI ASCII grid at ``path`` (keys lower case), from its first bytes only.

    Raises:
        SiteFileError: not a regular file, too large, or no usable header.
    """
    try:
        size = os.stat(path).st_size
        if not path.is_file():
            raise SiteFileError(f"DEM {path} is not a regular file")
        if size > MAX_ASCII_DEM_BYTES:
            raise SiteFileError(
                f"DEM {path} has {size} bytes; an ESRI ASCII DEM may have at most {MAX_ASCII_DEM_BYTES}"
            )
        with open(path, "rb") as handle:
            head = handle.read(_ASCII_HEADER_BYTES).decode("ascii", errors="replace")
    except OSError as exc:
        raise SiteFileError(f"cannot read DEM {path}: {exc.strerror or exc}") from None
    header: dict[str, float] = {}
    for line in head.splitlines()[:8]:
        tokens = line.split()
        if len(tokens) != 2 or not tokens[0][:1].isalpha():
            break
        if tokens[0].lower() not in _ASCII_KEYS:
            raise SiteFileError(
                f"DEM {path} is neither a GeoTIFF (.tif, .tiff) nor an ESRI ASCII grid: unexpected header line "
                f"{line.strip()[:60]!r}"
            )
        try:
            header[tokens[0].lower()] = float(tokens[1])
        except ValueError:
            raise SiteFileError(f"DEM {path}: header value is not a number: {line.strip()!r}") from None
    missing = [k for k in ("ncols", "nrows", "cellsize") if k not in header]
    if missing:
        raise SiteFileError(
            f"DEM {path} is neither a GeoTIFF (.tif, .tiff) nor an ESRI ASCII grid: its header lacks {missing}"
        )
    return header


def _ascii_dem(path: Path, crs: str | None) -> SiteDem:
    """The facts of an ESRI ASCII DEM (CRS from ``crs`` or guessed as degrees, see the module docstring)."""
    h = _ascii_header(path)
    rows, cols, cell = int(h["nrows"]), int(h["ncols"]), h["cellsize"]
    if rows < 2 or cols < 2 or not cell > 0:
        raise SiteFileError(f"DEM {path}: nrows and ncols must be >= 2 and cellsize > 0, got {rows}, {cols}, {cell}")
    if rows * cols > MAX_DEM_CELLS:
        raise SiteFileError(
            f"DEM {path} declares {rows} x {cols} = {rows * cols} cells; at most {MAX_DEM_CELLS} are read "
            "(crop the DEM to the site first)"
        )
    x0 = h["xllcorner"] if "xllcorner" in h else h.get("xllcenter", 0.0) - cell / 2
    y0 = h["yllcorner"] if "yllcorner" in h else h.get("yllcenter", 0.0) - cell / 2
    bounds = (x0, x0 + cols * cell, y0, y0 + rows * cell)
    if crs is None:
        lonlat = -180 <= bounds[0] and bounds[1] <= 180 and -90 <= bounds[2] and bounds[3] <= 90
        if cell >= _GEOGRAPHIC_CELL or not lonlat:
            raise SiteFileError(
                f"DEM {path} is an ESRI ASCII grid (no CRS of its own) with cell size {cell:g} and extent x "
                f"[{bounds[0]:g}, {bounds[1]:g}], y [{bounds[2]:g}, {bounds[3]:g}]: give its CRS as dem.crs "
                "(e.g. 'EPSG:32613' for UTM zone 13N)"
            )
        crs = "EPSG:4326"
    geographic = bool(crs_of(crs, f"dem.crs of {path}").is_geographic)
    return SiteDem(str(path), "esri_ascii", crs, geographic, bounds, cell, (rows, cols))


def _geotiff_dem(path: Path, crs: str | None) -> SiteDem:
    """The facts of a GeoTIFF DEM; ``crs`` must match its own (or stand in when it has none)."""
    try:
        header = read_geotiff_header(path)
    except GeometryError as exc:
        raise SiteFileError(f"DEM: {exc}") from None
    if header.crs_wkt:
        own = crs_of(header.crs_wkt, f"the CRS of {path}")
        if crs is not None and not own.equals(crs_of(crs, f"dem.crs of {path}"), ignore_axis_order=True):
            raise SiteFileError(
                f"dem.crs {crs!r} does not match the CRS of GeoTIFF {path} ({own.name}, {own.to_string()}); "
                "drop dem.crs or fix it"
            )
        crs_text, geographic = header.crs_wkt, header.geographic
    elif crs is not None:
        crs_text, geographic = crs, bool(crs_of(crs, f"dem.crs of {path}").is_geographic)
    else:
        raise SiteFileError(f"GeoTIFF {path} has no CRS: give it as dem.crs (e.g. 'EPSG:4326')")
    return SiteDem(
        str(path), "geotiff", crs_text, geographic, header.bounds, header.cell, (header.height, header.width)
    )


def open_dem(path: str | Path, crs: str | None = None) -> SiteDem:
    """The header facts of the DEM at ``path`` (GeoTIFF by its ending, else ESRI ASCII); no cell is read.

    Raises:
        SiteFileError: missing, unreadable, too large, malformed, or a CRS that is unknown, missing or does not
            match the file's own.
    """
    file = Path(path).resolve()
    if not file.is_file():
        raise SiteFileError(f"DEM {file} not found")
    return _geotiff_dem(file, crs) if is_geotiff(file) else _ascii_dem(file, crs)


def _outline(region: tuple[tuple[float, float], tuple[float, float]], per_side: int = 16) -> np.ndarray[Any, Any]:
    """(4 per_side, 2) points along the rectangle ``region`` = ((x0, x1), (y0, y1))."""
    (x0, x1), (y0, y1) = region
    t = np.linspace(0.0, 1.0, per_side, endpoint=False)
    xs = np.concatenate([x0 + t * (x1 - x0), np.full_like(t, x1), x1 - t * (x1 - x0), np.full_like(t, x0)])
    ys = np.concatenate([np.full_like(t, y0), y0 + t * (y1 - y0), np.full_like(t, y1), y1 - t * (y1 - y0)])
    return np.stack([xs, ys], axis=1)


def _lonlat_box(dem: SiteDem) -> str:
    """Where the DEM tile is on the globe: its longitude and latitude range, as text."""
    from pyproj import Transformer

    x0, x1, y0, y1 = dem.bounds
    if dem.geographic:
        lon, lat = np.array([x0, x1]), np.array([y0, y1])
    else:
        to_wgs = Transformer.from_crs(crs_of(dem.crs, "DEM CRS"), WGS84, always_xy=True)
        lon, lat = to_wgs.transform(np.array([x0, x1, x0, x1]), np.array([y0, y0, y1, y1]))
    return f"longitude [{np.min(lon):.4f}, {np.max(lon):.4f}], latitude [{np.min(lat):.4f}, {np.max(lat):.4f}]"


def check_covers(dem: SiteDem, frame: SiteFrame, region: tuple[tuple[float, float], tuple[float, float]]) -> None:
    """Refuse ``dem`` unless it holds the lattice-frame rectangle ``region`` = ((x0, x1), (y0, y1)) metres.

    The rectangle's outline is projected into the DEM's CRS and must lie one cell inside the grid's cell
    centres (room for bilinear sampling).

    Raises:
        SiteFileError: the DEM does not cover it (its tile and the origin named, in longitude and latitude).
    """
    points = _outline(region)
    gx, gy = frame.from_lattice(points[:, 0], points[:, 1], dem.crs)
    x0, x1, y0, y1 = dem.bounds
    inset = 1.5 * dem.cell
    inside = bool(np.isfinite(gx).all() and np.isfinite(gy).all())
    inside = inside and bool(gx.min() >= x0 + inset and gx.max() <= x1 - inset)
    inside = inside and bool(gy.min() >= y0 + inset and gy.max() <= y1 - inset)
    if not inside:
        (rx0, rx1), (ry0, ry1) = region
        raise SiteFileError(
            f"DEM {dem.path} does not cover the lattice around the origin: the tile spans {_lonlat_box(dem)}; "
            f"the origin is at latitude {frame.latitude:.4f}, longitude {frame.longitude:.4f}, and the terrain "
            f"needs x [{rx0:g}, {rx1:g}] m, y [{ry0:g}, {ry1:g}] m around it (heading {frame.heading_deg:g} deg); "
            "use a DEM tile of the site, or check the origin and the DEM's CRS"
        )


def check_known_heights(
    dem: SiteDem, frame: SiteFrame, region: tuple[tuple[float, float], tuple[float, float]]
) -> None:
    """Refuse ``dem`` when a cell under the lattice-frame rectangle ``region`` is NODATA (or not finite).

    Reads the DEM (after :func:`open_dem` bounded its size) and looks at the cells of the rectangle's bounding
    box in the DEM's grid.

    Raises:
        SiteFileError: unreadable cells, or NODATA under the lattice (how many, and where the first is).
    """
    try:
        grid = read_geotiff(dem.path)[0] if dem.kind == "geotiff" else read_esri_ascii(dem.path)
    except GeometryError as exc:
        raise SiteFileError(f"DEM: {exc}") from None
    points = _outline(region)
    gx, gy = frame.from_lattice(points[:, 0], points[:, 1], dem.crs)
    ox, oy = (float(v) for v in grid.origin)
    cell = float(grid.cell_size)
    rows, cols = grid.heights.shape
    j0, j1 = max(int(np.floor((gx.min() - ox) / cell)), 0), min(int(np.ceil((gx.max() - ox) / cell)), cols - 1)
    i0, i1 = max(int(np.floor((gy.min() - oy) / cell)), 0), min(int(np.ceil((gy.max() - oy) / cell)), rows - 1)
    block = grid.heights[i0 : i1 + 1, j0 : j1 + 1]
    unknown = np.argwhere(np.isnan(block))
    if unknown.size:
        i, j = unknown[0] + (i0, j0)
        raise SiteFileError(
            f"DEM {dem.path} has {len(unknown)} NODATA cell(s) under the lattice, the first at x {ox + j * cell:.6f}, "
            f"y {oy + i * cell:.6f} (its CRS); fill them (e.g. gdal_fillnodata) or move the origin"
        )
