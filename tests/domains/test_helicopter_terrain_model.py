"""Tests of the terrain world model's grid cache (the model's draws are tested in test_helicopter_worlds)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from drd_planner.domains.helicopter_terrain_model import TerrainGrids, TerrainModel
from drd_planner.domains.helicopter_world_frame import WorldFrame
from drd_planner.domains.helicopter_world_params import TerrainParams
from drd_planner.exceptions import ProblemError


def _grid(path: Path, value: float, size: int = 60) -> Path:
    yy, xx = np.mgrid[0:size, 0:size]
    heights = value + 20.0 * np.sin(xx / 5.0) * np.cos(yy / 7.0)
    rows = "\n".join(" ".join(f"{v:.3f}" for v in row) for row in heights)
    path.write_text(f"NCOLS {size}\nNROWS {size}\nXLLCORNER 0\nYLLCORNER 0\nCELLSIZE 30\n{rows}\n", encoding="ascii")
    return path


def test_grids_are_read_once_per_file_version(tmp_path: Path) -> None:
    grids = TerrainGrids(size=1)
    a = _grid(tmp_path / "a.asc", 100.0)
    first = grids.load(a)
    assert grids.load(a) is first
    assert len(grids) == 1
    _grid(a, 200.0)
    os.utime(a, ns=(first_ns := a.stat().st_mtime_ns + 10**9, first_ns))
    second = grids.load(a)
    assert second is not first
    assert second.heights.mean() > first.heights.mean()
    grids.load(_grid(tmp_path / "b.asc", 0.0))
    assert len(grids) == 1  # the least recently used grid went
    with pytest.raises(ProblemError, match="not found"):
        grids.load(tmp_path / "missing.asc")
    (tmp_path / "bad.asc").write_text("ncols 2\n", encoding="ascii")
    with pytest.raises(ProblemError, match="cannot use terrain grid"):
        grids.load(tmp_path / "bad.asc")
    with pytest.raises(ValueError, match="at least one grid"):
        TerrainGrids(size=0)


def test_model_draws_through_its_cache(tmp_path: Path) -> None:
    path = _grid(tmp_path / "hills.asc", 300.0, size=120)
    model = TerrainModel()
    frame = WorldFrame((0.0, 300.0), (-100.0, 100.0), 50.0, 25.0, ((0.0, 0.0, 65.0),), 6.0, 40.0)
    params = TerrainParams(path=str(path), metres_per_cell=(5.0, 8.0), nofly=0)
    one = model.draw(np.random.default_rng(3), params, frame)
    two = model.draw(np.random.default_rng(3), params, frame)
    assert np.array_equal(one.terrain.heights, two.terrain.heights)
    assert one.info == two.info
    assert len(model.grids) == 1
    assert one.wires == ()
    assert one.solids == ()


def test_relief_null_keeps_the_grids_own_heights(tmp_path: Path) -> None:
    path = _grid(tmp_path / "hills.asc", 300.0, size=120)  # heights 300 +- 20 m: a 40 m span at most
    model = TerrainModel()
    frame = WorldFrame((0.0, 300.0), (-100.0, 100.0), 50.0, 25.0, ((0.0, 0.0, 65.0),), 6.0, 40.0)
    scaled = model.draw(np.random.default_rng(3), TerrainParams(path=str(path), nofly=0), frame)
    own = model.draw(np.random.default_rng(3), TerrainParams(path=str(path), relief=None, nofly=0), frame)
    assert scaled.info["relief"] >= 80.0  # the default draws a relief in [80, 200] m
    assert 0.0 < own.info["relief"] <= 40.0
    span = np.ptp(own.terrain.heights)
    assert span <= 40.0 + 1e-6  # only shifted (and capped at the pads), never stretched
    with pytest.raises(ProblemError, match="relief"):
        TerrainParams(relief=(0.0, 10.0))


def test_cells_longer_north_south_stretch_the_crop_along_y(tmp_path: Path) -> None:
    """Issue 33 item 11: ``cell_aspect`` 2 makes a source row twice as long, so heights change half as fast in y."""
    size = 120
    heights = np.repeat(2.0 * np.arange(size, dtype=np.float64)[:, None], size, axis=1)  # 2 m per row
    rows = "\n".join(" ".join(f"{v:.3f}" for v in row) for row in heights)
    path = tmp_path / "ramp.asc"
    path.write_text(f"NCOLS {size}\nNROWS {size}\nXLLCORNER 0\nYLLCORNER 0\nCELLSIZE 30\n{rows}\n", encoding="ascii")
    frame = WorldFrame((0.0, 300.0), (-100.0, 100.0), 50.0, 25.0, ((0.0, 0.0, 65.0),), 6.0, 40.0)
    common = {"path": str(path), "metres_per_cell": (10.0, 10.0), "relief": None, "rotation_deg": (0.0, 0.0)}
    slopes = []
    for aspect in (1.0, 2.0):
        params = TerrainParams(**common, cell_aspect=aspect, mirror=0.0, site=(0.5, 0.5), nofly=0)  # type: ignore[arg-type]
        drawn = TerrainModel().draw(np.random.default_rng(3), params, frame)
        along_y = np.diff(drawn.terrain.heights, axis=0) / drawn.terrain.cell_size
        slopes.append(float(np.median(np.abs(along_y))))
        assert ("cell_aspect" in drawn.info) == (aspect != 1.0)
    assert slopes[0] == pytest.approx(0.2, rel=1e-6)  # 2 m per 10 m row
    assert slopes[1] == pytest.approx(0.1, rel=1e-6)  # 2 m per 20 m row
    with pytest.raises(ProblemError, match="cell_aspect"):
        TerrainParams(cell_aspect=0.0)
