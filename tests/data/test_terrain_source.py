"""Tests of ``drd build-dataset --domain helicopter --terrain FILE``: the terrain model on the user's grid.

The grid is written by the test (an ESRI ASCII file of smooth seeded hills, 30 m cells, UTM-like coordinates);
the helicopter is the small 300 m corridor of the domain tests.
"""

from __future__ import annotations

import json
import shlex
from pathlib import Path

import numpy as np
import pytest
from test_dataset_builder import GridDomain

from drd_planner.cli.build_dataset import main
from drd_planner.data.dataset_file import load_dataset
from drd_planner.data.terrain_source import TerrainWorlds, resolve, site_fractions, terrain_keys
from drd_planner.data.world_sources import FileRecord, TerrainFile
from drd_planner.domains.base import domain_from_spec
from drd_planner.exceptions import DatasetError
from drd_planner.geometry.terrain import read_esri_ascii

HELI = {"lattice": {"x_range": [0.0, 300.0], "y_range": [-100.0, 100.0], "goal": [300.0, 0.0]}}
ROWS, COLS, CELL = 60, 80, 30.0
X0, Y0 = 450_000.0, 4_400_000.0  # the lower-left corner (UTM-like metres)


def write_grid(path: Path, cell: float = CELL, origin: tuple[float, float] = (X0, Y0)) -> Path:
    """A ROWS x COLS ESRI ASCII grid of seeded smooth hills (heights 1500-1800 m), rows north to south."""
    rng = np.random.default_rng(5)
    yy, xx = np.mgrid[0:ROWS, 0:COLS]
    heights = 1500.0 + sum(
        h * np.exp(-((xx - cx) ** 2 + (yy - cy) ** 2) / (2 * s**2))
        for h, cx, cy, s in zip(
            rng.uniform(50, 300, 6),
            rng.uniform(0, COLS, 6),
            rng.uniform(0, ROWS, 6),
            rng.uniform(4, 12, 6),
            strict=True,
        )
    )
    header = (
        f"ncols {COLS}\nnrows {ROWS}\nxllcorner {origin[0]}\nyllcorner {origin[1]}\ncellsize {cell}\n"
        "NODATA_value -9999\n"
    )
    rows = "\n".join(" ".join(f"{v:.2f}" for v in row) for row in heights[::-1])
    path.write_text(header + rows + "\n")
    return path


@pytest.fixture(scope="module")
def grid(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_grid(tmp_path_factory.mktemp("terrain") / "site.asc")


def test_the_site_becomes_grid_fractions(grid: Path) -> None:
    field = read_esri_ascii(grid)
    # Grid point [0, 0] is the centre of the lower-left cell, half a cell inside the corner.
    first = (X0 + CELL / 2, Y0 + CELL / 2)
    assert site_fractions(field, first, "g") == [0.0, 0.0]
    last = (X0 + CELL / 2 + (COLS - 1) * CELL, Y0 + CELL / 2 + (ROWS - 1) * CELL)
    assert site_fractions(field, last, "g") == [1.0, 1.0]
    row, col = site_fractions(field, (first[0] + 20 * CELL, first[1] + 10 * CELL), "g")
    assert row == pytest.approx(10 / (ROWS - 1))
    assert col == pytest.approx(20 / (COLS - 1))
    with pytest.raises(DatasetError, match=r"--site 0,0 lies outside the grid g: x in \[450015, 452385\]"):
        site_fractions(field, (0.0, 0.0), "g")


def test_flags_map_onto_terrain_spec_keys(grid: Path, tmp_path: Path) -> None:
    field = read_esri_ascii(grid)
    centre = (X0 + 40 * CELL, Y0 + 30 * CELL)
    keys = terrain_keys(TerrainFile(str(grid), site=centre, site_jitter=25.0, crop="as-is"), field)
    assert keys["path"] == str(grid)
    assert keys["site_jitter"] == 25.0
    assert keys["rotation_deg"] == [0.0, 0.0]
    assert keys["mirror"] == 0.0
    assert keys["metres_per_cell"] == [CELL, CELL]
    assert keys["relief"] is None
    scaled = terrain_keys(TerrainFile(str(grid), crop="as-is", crop_scale=(12.0, 15.0)), field)
    assert scaled["metres_per_cell"] == [12.0, 15.0]
    assert "site" not in scaled
    # Issue 33 item 11: a geographic grid's cells are not square. At 40 degrees north a cell of 0.00083
    # degrees spans about 71 m east-west and 92 m north-south: the crop takes both (no more 27 % error).
    geo = write_grid(tmp_path / "geo.asc", cell=0.00083, origin=(-105.5, 40.0))
    degrees = read_esri_ascii(geo)
    at_40 = terrain_keys(TerrainFile(str(geo), site=(-105.45, 40.01), crop="as-is"), degrees)
    east, north = at_40["metres_per_cell"][0], at_40["metres_per_cell"][0] * at_40["cell_aspect"]
    assert east == pytest.approx(70.9, abs=0.1)
    assert north == pytest.approx(92.1, abs=0.1)
    assert at_40["metres_per_cell"][1] == east
    assert at_40["relief"] is None
    # --crop-scale sets the east-west metres; the aspect still comes from the latitude.
    scaled_geo = terrain_keys(TerrainFile(str(geo), crop="as-is", crop_scale=(90.0, 90.0)), degrees)
    assert scaled_geo["metres_per_cell"] == [90.0, 90.0]
    assert scaled_geo["cell_aspect"] > 1.29
    assert "cell_aspect" not in keys  # a projected grid's cells are square
    nowhere = read_esri_ascii(write_grid(tmp_path / "nowhere.asc", cell=0.00083))  # y values 4.4e6: not degrees
    with pytest.raises(DatasetError, match=r"cell size 0.00083 \(degrees\?\) but its y values"):
        terrain_keys(TerrainFile(str(tmp_path / "nowhere.asc"), crop="as-is"), nowhere)


def test_a_domain_without_a_terrain_model_is_refused(grid: Path) -> None:
    with pytest.raises(DatasetError, match="--terrain needs a domain with a 'terrain' world model; domain 'grid_test'"):
        resolve(TerrainFile(str(grid)), GridDomain(), {}, 3)


@pytest.mark.slow
def test_a_terrain_build_draws_seeded_crops_of_the_users_grid(
    grid: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "terrain.npz"
    centre = f"{X0 + 40 * CELL},{Y0 + 30 * CELL}"
    argv = [
        "build-dataset",
        "--domain",
        "helicopter",
        "--domain-spec",
        json.dumps(HELI),
        "--terrain",
        str(grid),
    ]
    argv += ["--site", centre, "--site-jitter", "20", "--crop", "as-is", "--worlds", "4", "--seed", "2"]
    assert main([*argv, "--workers", "1", "--out", str(out)]) == 0
    assert "worlds: terrain model on " in capsys.readouterr().out
    ds = load_dataset(out)
    terrain = ds.domain_spec["models"]["terrain"]
    assert terrain["path"] == str(grid)
    assert terrain["site"] == pytest.approx([29.5 / 59, 39.5 / 79])
    assert terrain["mirror"] == 0.0
    assert ds.world_model == "terrain"
    source = ds.provenance["world_source"]
    assert source["file"]["sha256"] == FileRecord.of(grid).sha256
    assert source["grid"]["rows"] == ROWS
    domain = domain_from_spec("helicopter", ds.domain_spec)
    edges = np.arange(domain.graph.num_edges)
    expected = [domain.checker(domain.make_world("terrain", int(s))).check_many(edges) for s in ds.world_seeds]
    assert np.array_equal(ds.X, np.array(expected))
    assert ds.world_model_params["path"] == str(grid)
    # The recorded command (with --terrain and its flags) recreates the same bytes.
    again = tmp_path / "again.npz"
    assert main([*shlex.split(ds.provenance["command"])[1:], "--workers", "2", "--out", str(again)]) == 0
    assert again.read_bytes() == out.read_bytes()


def test_a_changed_grid_is_refused_by_the_worker(tmp_path: Path) -> None:
    path = write_grid(tmp_path / "g.asc")
    record = FileRecord.of(path)
    assert TerrainWorlds("terrain", [record]).records == (record,)
    path.write_text(path.read_text().replace("cellsize 30.0", "cellsize 31.0"))
    with pytest.raises(DatasetError, match=r"g\.asc changed since the build was planned"):
        TerrainWorlds("terrain", [record])


def test_terrain_needs_a_number_of_worlds(grid: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(
            [
                "build-dataset",
                "--domain",
                "helicopter",
                "--terrain",
                str(grid),
                "--seed",
                "0",
                "--out",
                "x.npz",
            ]
        )
    assert "the following arguments are required: --worlds" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["build-dataset", "--domain", "helicopter", "--terrain", str(grid), "--site", "1,2,3"])
    assert "give 2 finite number(s), comma-separated" in capsys.readouterr().err
