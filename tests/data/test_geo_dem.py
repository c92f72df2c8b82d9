"""A site's DEM: header facts, CRS agreement, size bounds from the header, and coverage of the lattice."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import REPO_ROOT

from drd_planner.data import geo_dem
from drd_planner.data.geo_dem import check_covers, open_dem
from drd_planner.data.geo_frame import SiteFrame
from drd_planner.exceptions import SiteFileError

pytest.importorskip("rasterio")

DEM = REPO_ROOT / "sites" / "front_range" / "dem.tif"
LATTICE = ((-200.0, 2700.0), (-1400.0, 1400.0))


def test_the_bundled_geotiff_is_geographic_and_covers_its_lattice() -> None:
    dem = open_dem(DEM)
    assert dem.kind == "geotiff"
    assert dem.geographic
    assert dem.units == "degrees"
    assert dem.shape == (48, 59)
    x0, x1, y0, y1 = dem.bounds
    assert x0 < -105.4617 < x1
    assert y0 < 40.1825 < y1
    check_covers(dem, SiteFrame(40.1825, -105.4617, 0.0), LATTICE)


def test_a_tile_elsewhere_names_where_the_tile_and_the_origin_are() -> None:
    dem = open_dem(DEM)
    with pytest.raises(SiteFileError, match=r"tile spans longitude \[-105\.4896.*origin is at latitude 47\.0000"):
        check_covers(dem, SiteFrame(47.0, 8.0, 0.0), LATTICE)
    # turned by 90 degrees the lattice's 2.7 km x leaves the 4.1 km wide tile's east edge
    with pytest.raises(SiteFileError, match="does not cover the lattice"):
        check_covers(dem, SiteFrame(40.1825, -105.4617, 90.0), ((-200.0, 3000.0), (-1400.0, 1400.0)))


def test_a_crs_that_does_not_match_the_geotiff_is_refused() -> None:
    assert open_dem(DEM, "EPSG:4326").geographic
    with pytest.raises(SiteFileError, match="does not match the CRS of GeoTIFF"):
        open_dem(DEM, "EPSG:32613")


def _asc(path: Path, cell: float, x0: float, y0: float, rows: int = 3, cols: int = 3) -> Path:
    body = "\n".join(" ".join("1" for _ in range(cols)) for _ in range(rows))
    path.write_text(f"ncols {cols}\nnrows {rows}\nxllcorner {x0}\nyllcorner {y0}\ncellsize {cell}\n{body}\n")
    return path


def test_an_ascii_grid_needs_a_crs_unless_it_is_plainly_degrees(tmp_path: Path) -> None:
    dem = open_dem(_asc(tmp_path / "deg.asc", 0.001, -105.5, 40.1))
    assert dem.kind == "esri_ascii"
    assert dem.geographic
    assert dem.crs == "EPSG:4326"
    with pytest.raises(SiteFileError, match=r"give its CRS as dem\.crs"):
        open_dem(_asc(tmp_path / "utm.asc", 30.0, 470000.0, 4440000.0))
    projected = open_dem(tmp_path / "utm.asc", "EPSG:32613")
    assert not projected.geographic
    assert projected.bounds == (470000.0, 470090.0, 4440000.0, 4440090.0)


def test_oversized_grids_are_refused_from_the_header(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "big.asc"
    path.write_text("ncols 100000\nnrows 100000\nxllcorner 0\nyllcorner 0\ncellsize 0.001\n1 2 3\n")
    with pytest.raises(SiteFileError, match="100000 x 100000 = 10000000000 cells"):
        open_dem(path)
    monkeypatch.setattr(geo_dem, "MAX_ASCII_DEM_BYTES", 10)
    with pytest.raises(SiteFileError, match="an ESRI ASCII DEM may have at most 10"):
        open_dem(path)


def test_a_file_that_is_neither_kind_and_a_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "x.dat"
    path.write_text("hello world\n")
    with pytest.raises(SiteFileError, match="neither a GeoTIFF"):
        open_dem(path)
    with pytest.raises(SiteFileError, match="not found"):
        open_dem(tmp_path / "missing.tif")


def test_nodata_under_the_lattice_is_refused_and_elsewhere_allowed(tmp_path: Path) -> None:
    from drd_planner.data.geo_dem import check_known_heights
    from drd_planner.geometry.geotiff import read_geotiff, write_geotiff
    from drd_planner.geometry.terrain import Heightfield

    frame = SiteFrame(40.1825, -105.4617, 0.0)
    grid, _header = read_geotiff(DEM)
    check_known_heights(open_dem(DEM), frame, LATTICE)
    holes = np.array(grid.heights)
    holes[-1, 0] = np.nan  # the north-west corner cell: outside the lattice
    write_geotiff(tmp_path / "corner.tif", Heightfield(grid.origin, grid.cell_size, holes), "EPSG:4326")
    check_known_heights(open_dem(tmp_path / "corner.tif"), frame, LATTICE)
    holes[12, 20] = np.nan  # under the lattice
    write_geotiff(tmp_path / "hole.tif", Heightfield(grid.origin, grid.cell_size, holes), "EPSG:4326")
    with pytest.raises(SiteFileError, match=r"has 1 NODATA cell\(s\) under the lattice, the first at x -105\.47"):
        check_known_heights(open_dem(tmp_path / "hole.tif"), frame, LATTICE)
