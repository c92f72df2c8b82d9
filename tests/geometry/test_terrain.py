"""Heightfield: ESRI ASCII reading, interpolation, cropping, meshing, and terrain collision."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import SHARED_DATA

from drd_planner.exceptions import GeometryError
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Box
from drd_planner.geometry.terrain import Heightfield, arc_degrees_to_metres, read_esri_ascii
from drd_planner.geometry.terrain_collider import TerrainCollider

SRTM = SHARED_DATA / "terrain" / "srtm_front_range_144.asc"


def write(tmp_path: Path, text: str, name: str = "grid.asc") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


# --------------------------------------------------------------------------------------------------
# Reader


def test_reader_with_corner_header_flips_rows_and_reads_nodata(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        "ncols 3\nnrows 2\nxllcorner 100\nyllcorner 200\ncellsize 10\nNODATA_value -9999\n1 2 3\n4 -9999 6\n",
    )
    field = read_esri_ascii(path)
    np.testing.assert_array_equal(field.origin, [105.0, 205.0])  # half a cell inside the corner
    assert field.cell_size == 10.0
    assert field.shape == (2, 3)
    np.testing.assert_array_equal(field.heights[1], [1, 2, 3])  # first file row is the northern one
    assert field.heights[0, 0] == 4
    assert math.isnan(field.heights[0, 1])
    assert field.heights[0, 2] == 6
    assert field.extent == (105.0, 125.0, 205.0, 215.0)


def test_reader_with_center_header_any_case_and_layout(tmp_path: Path) -> None:
    values = " ".join(str(v) for v in range(20))
    path = write(tmp_path, f"NCOLS 5\nNROWS 4\nXLLCENTER -3.5\nYLLCenter 7\nCELLSIZE 0.5\n{values[:9]}\n{values[9:]}\n")
    field = read_esri_ascii(path)
    np.testing.assert_array_equal(field.origin, [-3.5, 7.0])
    assert field.shape == (4, 5)
    np.testing.assert_array_equal(field.heights[3], [0, 1, 2, 3, 4])
    np.testing.assert_array_equal(field.heights[0], [15, 16, 17, 18, 19])
    assert not np.isnan(field.heights).any()


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\n1 2 3 4\n", "cellsize"),
        ("ncols 2\nnrows 2\nxllcorner 0\nxllcenter 0\nyllcorner 0\ncellsize 1\n1 2 3 4\n", "exactly one"),
        ("ncols 2\nnrows 2\nyllcorner 0\ncellsize 1\n1 2 3 4\n", "exactly one"),
        ("ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n", "expected nrows"),
        ("ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 x 4\n", "numbers"),
        ("ncols 2\nnrows 1\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n", ">= 2"),
        ("ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\nbogus 3\n1 2 3 4\n", "unexpected header"),
        ("ncols 2\nnrows 2\nxllcorner zero\nyllcorner 0\ncellsize 1\n1 2 3 4\n", "not a number"),
        ("ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 0\n1 2 3 4\n", "cell size"),
    ],
)
def test_reader_rejects_bad_files(tmp_path: Path, text: str, message: str) -> None:
    with pytest.raises(GeometryError, match=message):
        read_esri_ascii(write(tmp_path, text))


def test_reader_missing_file(tmp_path: Path) -> None:
    with pytest.raises(GeometryError, match="cannot read"):
        read_esri_ascii(tmp_path / "absent.asc")


def test_shared_srtm_file() -> None:
    if not SRTM.is_file():
        pytest.skip(f"shared terrain {SRTM} not present (set DRD_SHARED_DATA to its parent)")
    field = read_esri_ascii(SRTM)
    assert field.shape == (144, 144)
    assert field.cell_size == pytest.approx(0.000833333333)  # 3 arc-seconds: the header is in degrees
    assert field.origin[0] == pytest.approx(-105.560416666684 + 0.000833333333 / 2)
    assert not np.isnan(field.heights).any()
    assert field.heights[143, 0] == 2588  # first value of the file: the north-west corner
    assert (np.nanmin(field.heights), np.nanmax(field.heights)) == (2186.0, 3345.0)
    east_west, north_south = arc_degrees_to_metres(field.cell_size, latitude_degrees=field.origin[1])
    assert north_south == pytest.approx(92.8, abs=0.5)
    assert east_west == pytest.approx(71.0, abs=0.5)
    metric = field.with_cell_size(90.0)
    assert metric.extent == (0.0, 143 * 90.0, 0.0, 143 * 90.0)
    np.testing.assert_array_equal(metric.heights, field.heights)


# --------------------------------------------------------------------------------------------------
# Interpolation


CORNER = Heightfield((0.0, 0.0), 1.0, [[0.0, 0.0], [0.0, 1.0]])  # only the (x=1, y=1) corner is raised


def test_bilinear_and_triangle_heights_at_known_points() -> None:
    xy = [[0.0, 0.0], [1.0, 1.0], [0.5, 0.5], [0.75, 0.25], [0.25, 0.75]]
    np.testing.assert_allclose(CORNER.height_at(xy), [0.0, 1.0, 0.25, 0.1875, 0.1875])
    np.testing.assert_allclose(CORNER.height_at(xy, interpolation="triangles"), [0.0, 1.0, 0.5, 0.25, 0.25])


def test_planar_field_is_reproduced_exactly() -> None:
    ys, xs = np.mgrid[0:4, 0:5] * 2.0
    field = Heightfield((10.0, 20.0), 2.0, 3.0 * xs - 2.0 * ys + 7.0)
    xy = np.array([[11.3, 20.4], [17.9, 25.5], [14.0, 22.0]])
    expected = 3.0 * (xy[:, 0] - 10.0) - 2.0 * (xy[:, 1] - 20.0) + 7.0
    np.testing.assert_allclose(field.height_at(xy), expected)
    np.testing.assert_allclose(field.height_at(xy, interpolation="triangles"), expected)


def test_outside_and_unknown_heights_are_nan() -> None:
    field = Heightfield((0.0, 0.0), 1.0, [[0.0, 1.0, 2.0], [np.nan, 1.0, 2.0]])
    got = field.height_at([[-0.1, 0.0], [2.1, 0.5], [0.5, 0.5], [1.5, 0.5], [2.0, 1.0]])
    assert np.isnan(got[:3]).all()
    np.testing.assert_allclose(got[3:], [1.5, 2.0])
    # Outside the grid nothing is below; over the cell with the unknown corner the default "blocked" surface
    # is a wall at every height.
    assert field.below([[-0.5, 0.5, -100.0], [0.5, 0.5, 1e5], [1.5, 0.5, 0.0], [1.5, 0.5, 2.0]]).tolist() == [
        False,
        True,
        True,
        False,
    ]
    assert field.below([[1.5, 0.5, 2.0]], clearance=1.0).tolist() == [True]


def test_unknown_heights_options_fill_the_collision_surface() -> None:
    heights = [[0.0, 1.0, 2.0], [np.nan, 1.0, 2.0]]
    blocked = Heightfield((0.0, 0.0), 1.0, heights)
    assert blocked.unknown == "blocked"
    assert blocked.surface_heights[1, 0] == pytest.approx(2.0 + 1e6)
    assert math.isnan(blocked.heights[1, 0])  # the measured heights keep their NaN
    rim = Heightfield((0.0, 0.0), 1.0, heights, unknown="highest_neighbour")
    assert rim.surface_heights[1, 0] == 1.0  # neighbours 0, 1, 1
    assert rim.below([[0.5, 0.5, 1.5], [0.5, 0.5, 0.5]]).tolist() == [False, True]  # bilinear 0.75
    assert blocked.below([[0.5, 0.5, 1.5]]).tolist() == [True]
    assert rim.crop(x_range=(0.0, 1.0), y_range=(0.0, 1.0)).unknown == "highest_neighbour"
    assert rim.with_cell_size(2.0).unknown == "highest_neighbour"
    known = Heightfield((0.0, 0.0), 1.0, np.zeros((2, 2)))
    assert known.surface_heights is known.heights  # nothing to fill, nothing copied
    with pytest.raises(GeometryError, match="'blocked', 'highest_neighbour'"):
        Heightfield((0.0, 0.0), 1.0, heights, unknown="free")  # type: ignore[arg-type]


def test_highest_neighbour_fills_each_unknown_region_from_its_own_rim() -> None:
    heights = np.zeros((6, 8))
    heights[:, 4:] = 50.0  # a plateau on the east half
    heights[1:5, 1:3] = np.nan  # a 4 x 2 gap in the low west: its rim is all 0
    heights[2:4, 5:7] = np.nan  # a 2 x 2 gap inside the plateau: its rim is all 50
    field = Heightfield((0.0, 0.0), 1.0, heights, unknown="highest_neighbour")
    surface = field.surface_heights
    assert (surface[1:5, 1:3] == 0.0).all()
    assert (surface[2:4, 5:7] == 50.0).all()
    assert not np.isnan(surface).any()


def test_invalid_heightfields_and_queries() -> None:
    with pytest.raises(GeometryError, match="rows >= 2"):
        Heightfield((0.0, 0.0), 1.0, [[1.0, 2.0]])
    with pytest.raises(GeometryError, match="cell size"):
        Heightfield((0.0, 0.0), -1.0, np.zeros((2, 2)))
    with pytest.raises(GeometryError, match="origin"):
        Heightfield((0.0,), 1.0, np.zeros((2, 2)))
    with pytest.raises(GeometryError, match="infinite"):
        Heightfield((0.0, 0.0), 1.0, [[0.0, np.inf], [0.0, 0.0]])
    with pytest.raises(GeometryError, match="interpolation"):
        CORNER.height_at([[0.5, 0.5]], interpolation="cubic")  # type: ignore[arg-type]
    with pytest.raises(GeometryError, match="xy"):
        CORNER.height_at([[0.5, 0.5, 0.5]])


def test_crop_and_mesh() -> None:
    field = Heightfield((0.0, 0.0), 10.0, np.arange(20.0).reshape(4, 5))
    sub = field.crop(x_range=(10.0, 30.0), y_range=(5.0, 30.0))
    np.testing.assert_array_equal(sub.origin, [10.0, 10.0])
    np.testing.assert_array_equal(sub.heights, field.heights[1:4, 1:4])
    with pytest.raises(GeometryError, match="fewer than 2 x 2"):
        field.crop(x_range=(0.0, 5.0), y_range=(0.0, 30.0))
    mesh = field.to_mesh()
    assert mesh.faces.shape == (2 * 3 * 4, 3)
    np.testing.assert_array_equal(mesh.vertices[7], [20.0, 10.0, 7.0])
    holes = Heightfield((0.0, 0.0), 1.0, [[0.0, 0.0, 0.0], [0.0, np.nan, 0.0], [0.0, 0.0, 0.0]])
    # every cell has the unknown centre as a corner: no triangles at all
    with pytest.raises(GeometryError, match="no cell"):
        holes.to_mesh()


# --------------------------------------------------------------------------------------------------
# Collision against terrain


RIDGE = Heightfield((0.0, 0.0), 10.0, [[0.0, 100.0, 0.0]] * 3)  # a ridge at x = 10 along y, 100 m high


@pytest.mark.parametrize("tile_cells", [1, 8])
def test_ridge_just_above_misses_just_below_hits_wholly_below_is_blocked(tile_cells: int) -> None:
    scene = Scene()
    scene.add_terrain(RIDGE, tile_cells=tile_cells)
    assert not scene.spheres_collide([[10.0, 10.0, 101.5]], 1.0)
    assert scene.spheres_collide([[10.0, 10.0, 100.5]], 1.0)
    assert scene.spheres_collide([[10.0, 10.0, 50.0]], 1.0)  # 4.97 m from both slopes: under, not touching
    assert scene.spheres_collide([[5.0, 10.0, 30.0]], 1.0)
    # The slope z = 10 x: a point 10 m above it at x = 5 is only 10 / sqrt(101) = 0.995 m from it.
    assert scene.spheres_collide([[5.0, 10.0, 60.0]], 1.0)
    assert not scene.spheres_collide([[5.0, 10.0, 60.0]], 0.99)
    assert not scene.spheres_collide([[5.0, 10.0, 70.0]], 1.0)
    assert scene.collides(Box((2.0, 2.0, 2.0)), Pose((10.0, 10.0, 50.0)))
    assert not scene.collides(Box((2.0, 2.0, 2.0)), Pose((10.0, 10.0, 103.0)))


def test_srtm_peak_just_above_misses_just_below_hits() -> None:
    if not SRTM.is_file():
        pytest.skip(f"shared terrain {SRTM} not present (set DRD_SHARED_DATA to its parent)")
    field = read_esri_ascii(SRTM).with_cell_size(90.0)
    i, j = np.unravel_index(np.argmax(field.heights), field.shape)
    x, y, top = 90.0 * j, 90.0 * i, field.heights[i, j]
    scene = Scene()
    scene.add_terrain(field)
    assert not scene.spheres_collide([[x, y, top + 5.5]], 5.0)
    assert scene.spheres_collide([[x, y, top + 4.5]], 5.0)
    assert scene.spheres_collide([[x, y, top - 200.0]], 5.0)


def test_tiling_does_not_change_answers() -> None:
    rng = np.random.default_rng(3)
    field = Heightfield((0.0, 0.0), 4.0, 20.0 * rng.random((13, 11)))
    centres = rng.uniform((-5, -5, -2), (45, 53, 24), size=(300, 3))
    radii = rng.uniform(0.5, 6.0, size=300)
    answers = []
    for tile_cells in (1, 3, 100):
        scene = Scene()
        scene.add_terrain(field, tile_cells=tile_cells)
        answers.append(scene.spheres_collide_mask(centres, radii).tolist())
    assert answers[0] == answers[1] == answers[2]
    assert 30 < sum(answers[0]) < 270


def test_collider_rejects_empty_terrain_and_bad_tiles() -> None:
    with pytest.raises(GeometryError, match="tile_cells"):
        TerrainCollider(CORNER, tile_cells=0)
    with pytest.raises(GeometryError, match="no cell"):
        TerrainCollider(Heightfield((0.0, 0.0), 1.0, [[np.nan, 0.0], [0.0, 0.0]]))


def test_unknown_cells_are_blocked_by_default_or_at_their_highest_neighbour() -> None:
    heights = np.full((5, 5), 10.0)
    heights[2, 2] = np.nan  # the four cells around grid point (20, 20) are unknown
    heights[4, 4] = 30.0
    blocked = Scene()
    blocked.add_terrain(Heightfield((0.0, 0.0), 10.0, heights), tile_cells=2)
    assert blocked.spheres_collide([[20.0, 20.0, 10.0]], 1.0)
    assert blocked.spheres_collide([[15.0, 15.0, 0.0]], 1.0)
    assert blocked.spheres_collide([[15.0, 15.0, 5000.0]], 1.0)  # a wall at every height
    assert blocked.spheres_collide([[5.0, 5.0, 0.0]], 1.0)
    assert not blocked.spheres_collide([[5.0, 5.0, 12.0]], 1.0)  # known cells keep their surface
    rim = Scene()
    rim.add_terrain(Heightfield((0.0, 0.0), 10.0, heights, unknown="highest_neighbour"), tile_cells=2)
    assert rim.spheres_collide([[20.0, 20.0, 10.5]], 1.0)  # the gap is at its neighbours' 10 m
    assert not rim.spheres_collide([[20.0, 20.0, 11.5]], 1.0)
    assert not rim.spheres_collide([[15.0, 15.0, 5000.0]], 1.0)
