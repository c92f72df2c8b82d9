"""GeoTIFF DEMs: header checks before any pixel is read, the heights read back as written, crops."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from drd_planner.exceptions import GeometryError
from drd_planner.geometry.geotiff import (
    MAX_DEM_CELLS,
    crop_heightfield,
    is_geotiff,
    read_geotiff,
    read_geotiff_header,
    write_geotiff,
)
from drd_planner.geometry.terrain import Heightfield

rasterio = pytest.importorskip("rasterio")
from rasterio.transform import Affine  # noqa: E402


def _grid() -> Heightfield:
    heights = np.arange(20.0).reshape(4, 5) * 10.0
    heights[2, 3] = np.nan
    return Heightfield((-105.0, 40.0), 0.001, heights)


def test_written_heights_read_back_south_row_first_with_nodata_as_nan(tmp_path: Path) -> None:
    path = tmp_path / "dem.tif"
    grid = _grid()
    write_geotiff(path, grid, "EPSG:4326")
    back, header = read_geotiff(path)
    assert (header.width, header.height, header.bands) == (5, 4, 1)
    assert header.geographic
    np.testing.assert_allclose(back.origin, grid.origin, atol=1e-9)
    assert back.cell_size == pytest.approx(0.001)
    np.testing.assert_array_equal(np.isnan(back.heights), np.isnan(grid.heights))
    np.testing.assert_allclose(back.heights[~np.isnan(back.heights)], grid.heights[~np.isnan(grid.heights)])
    x0, x1, y0, y1 = header.bounds
    assert x0 == pytest.approx(-105.0005)
    assert x1 == pytest.approx(-104.9955)
    assert y0 == pytest.approx(39.9995)
    assert y1 == pytest.approx(40.0035)


def test_a_billion_cell_header_is_refused_before_any_pixel_is_read(tmp_path: Path) -> None:
    path = tmp_path / "huge.tif"
    with rasterio.open(
        path,
        "w",
        driver="GTiff",
        width=40000,
        height=40000,
        count=1,
        dtype="float32",
        crs="EPSG:4326",
        transform=Affine(0.001, 0.0, 0.0, 0.0, -0.001, 1.0),
        tiled=True,
        sparse_ok=True,
        compress="deflate",
    ):
        pass
    assert path.stat().st_size < 1 << 20  # small on disk, huge when read
    with pytest.raises(GeometryError, match=rf"40000 x 40000 x 1 = 1600000000 cells; at most {MAX_DEM_CELLS}"):
        read_geotiff(path)


def _raw(path: Path, transform: Affine) -> None:
    with rasterio.open(
        path, "w", driver="GTiff", width=3, height=3, count=1, dtype="float32", crs="EPSG:4326", transform=transform
    ) as dst:
        dst.write(np.zeros((3, 3), dtype=np.float32), 1)


def test_rotated_and_non_square_rasters_are_refused(tmp_path: Path) -> None:
    _raw(tmp_path / "rot.tif", Affine(0.001, 0.0005, 0.0, 0.0005, -0.001, 1.0))
    with pytest.raises(GeometryError, match="rotated or sheared"):
        read_geotiff_header(tmp_path / "rot.tif")
    _raw(tmp_path / "rect.tif", Affine(0.002, 0.0, 0.0, 0.0, -0.001, 1.0))
    with pytest.raises(GeometryError, match="pixels must be square"):
        read_geotiff_header(tmp_path / "rect.tif")


def test_a_file_that_is_not_a_tiff_gets_one_error(tmp_path: Path) -> None:
    path = tmp_path / "fake.tif"
    path.write_text("ncols 3\n")
    with pytest.raises(GeometryError, match="cannot read GeoTIFF"):
        read_geotiff(path)
    assert is_geotiff(path)
    assert is_geotiff("A.TIFF")
    assert not is_geotiff("a.asc")


def test_crop_keeps_the_points_inside_the_box() -> None:
    grid = _grid()
    crop = crop_heightfield(grid, (-104.9995, -104.9965), (40.0005, 40.0025))
    assert crop.heights.shape == (2, 3)
    np.testing.assert_allclose(crop.origin, (-104.999, 40.001))
    np.testing.assert_array_equal(crop.heights[0], grid.heights[1, 1:4])
    with pytest.raises(GeometryError, match="holds 0 x"):
        crop_heightfield(grid, (0.0, 1.0), (40.0, 41.0))


def test_the_convert_dem_tool_crops_an_ascii_grid_into_a_geotiff(tmp_path: Path) -> None:
    import subprocess
    import sys

    from conftest import REPO_ROOT

    source = tmp_path / "in.asc"
    rows = "\n".join(" ".join(str(10 * r + c) for c in range(6)) for r in range(5))  # north row first
    source.write_text(f"ncols 6\nnrows 5\nxllcorner -105.0\nyllcorner 40.0\ncellsize 0.001\n{rows}\n")
    out = tmp_path / "out.tif"
    tool = REPO_ROOT / "scripts" / "tools" / "convert_dem.py"
    crop = "--crop=-104.9986,-104.9974,40.0010,40.0030"
    done = subprocess.run([sys.executable, str(tool), str(source), str(out), crop], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith(f"wrote {out}: 2 x 2 cells")
    grid, header = read_geotiff(out)
    assert header.geographic
    np.testing.assert_allclose(grid.heights, [[31, 32], [21, 22]])  # rows south to north
    bad = subprocess.run(
        [sys.executable, str(tool), str(source), str(out), "--crop=0,1,0,1"], capture_output=True, text=True
    )
    assert bad.returncode == 2
    assert bad.stderr.startswith("convert_dem: error: the crop")
