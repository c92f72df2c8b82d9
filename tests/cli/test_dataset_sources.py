"""Tests of the world-source flags of ``drd build-dataset``: parsing, combinations, the source requests."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import NoReturn

import pytest

from drd_planner.cli.dataset_sources import (
    add_source_arguments,
    check_required,
    source_from_args,
    source_summary,
)
from drd_planner.data.world_sources import MapBags, SceneFolder, SiteFile, TerrainFile


class ArgError(Exception):
    """What the test parser's ``error`` raises instead of exiting."""


def _parse(argv: list[str]) -> tuple[argparse.Namespace, argparse.ArgumentParser]:
    parser = argparse.ArgumentParser(prog="drd build-dataset")
    for flag in ("--world-model", "--seed", "--out"):
        parser.add_argument(flag)
    parser.add_argument("--worlds", type=int)
    add_source_arguments(parser)
    return parser.parse_args(argv), parser


def _error(message: str) -> NoReturn:
    raise ArgError(message)


def test_each_source_flag_gives_its_request(tmp_path: Path) -> None:
    args, _ = _parse(["--scenes", str(tmp_path), "--no-requests"])
    assert source_from_args(args, _error) == SceneFolder(str(tmp_path), requests=False)
    args, _ = _parse(["--bags", "a.mcap", "b.mcap", "--frame", "odom"])
    bags = source_from_args(args, _error)
    assert isinstance(bags, MapBags)
    assert [Path(f).name for f in bags.files] == ["a.mcap", "b.mcap"]
    assert bags.frame == "odom"
    args, _ = _parse(["--terrain", "t.asc", "--site", "5e5,4.4e6", "--site-jitter", "40", "--crop-scale", "25"])
    terrain = source_from_args(args, _error)
    assert isinstance(terrain, TerrainFile)
    assert terrain.site == (5e5, 4.4e6)
    assert terrain.site_jitter == 40.0
    assert terrain.crop == "random"
    assert terrain.crop_scale == (25.0, 25.0)
    west = TerrainFile("t.asc", site=(-105.5, 40.15))
    again, _ = _parse(west.argv())  # a negative X survives the round trip through the flags
    assert source_from_args(again, _error) == west
    args, _ = _parse(["--site-file", "site.yaml"])
    site = source_from_args(args, _error)
    assert site == SiteFile("site.yaml")
    assert Path(site.path).is_absolute()
    args, _ = _parse(["--world-model", "forest"])
    assert source_from_args(args, _error) is None


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--site", "1"], "give 2 finite number(s), comma-separated"),
        (["--site", "a,b"], "is not comma-separated numbers"),
        (["--crop-scale", "0"], "metres per cell must be > 0"),
        (["--crop-scale", "30,20"], "(and LO <= HI)"),
        (["--site-jitter", "-1"], "must be non-negative"),
        (["--crop", "tilted"], "invalid choice: 'tilted'"),
    ],
)
def test_bad_values_are_argparse_errors(argv: list[str], message: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        _parse(["--terrain", "t.asc", *argv])
    assert message in capsys.readouterr().err


def test_required_arguments_depend_on_the_source() -> None:
    args, _ = _parse(["--scenes", "d"])
    with pytest.raises(ArgError, match=r"^the following arguments are required: --seed, --out$"):
        check_required(args, _error)
    args, _ = _parse(["--terrain", "t.asc", "--seed", "0", "--out", "x"])
    with pytest.raises(ArgError, match=r"^the following arguments are required: --worlds$"):
        check_required(args, _error)
    args, _ = _parse(["--scenes", "d", "--seed", "0", "--out", "x"])
    check_required(args, _error)
    args, _ = _parse(["--site-file", "s.yaml", "--seed", "0"])  # --worlds comes from the site file
    with pytest.raises(ArgError, match=r"^the following arguments are required: --out$"):
        check_required(args, _error)


def test_site_file_goes_alone(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        _parse(["--site-file", "s.yaml", "--terrain", "t.asc"])
    assert "not allowed with argument" in capsys.readouterr().err
    args, _ = _parse(["--site-file", "s.yaml", "--site", "1,2"])
    with pytest.raises(ArgError, match="--site goes with --terrain"):
        source_from_args(args, _error)
    args, _ = _parse(["--site-file", "s.yaml", "--world-model", "corridors"])
    with pytest.raises(ArgError, match="--world-model: not allowed with --site-file"):
        source_from_args(args, _error)


def test_the_summary_says_where_the_worlds_came_from() -> None:
    assert source_summary({"command": "drd build-dataset"}) is None
    bags = {"kind": "bags", "frame": "map", "files": [{"path": "/b/x.mcap"}], "snapshots": [{}, {}]}
    assert source_summary({"world_source": bags}) == "worlds: 2 map snapshot(s) of x.mcap in frame 'map'"
    scenes = {"kind": "scenes", "folder": "/s", "scenes": [{}] * 3, "requests": []}
    assert source_summary({"world_source": scenes}) == "worlds: 3 scene file(s) of /s"
    terrain = {
        "kind": "terrain",
        "file": {"path": "/t.asc"},
        "spec_keys": {"models.terrain.site_jitter": 5.0},
    }
    assert source_summary({"world_source": terrain}) == (
        "worlds: terrain model on /t.asc (models.terrain.site_jitter=5.0)"
    )
    site = {"kind": "site", "site": "ridge", "files": [{}] * 3, "dem": {"path": "/d.tif"}, "lines": ["a"], "zones": []}
    assert source_summary({"world_source": site}) == (
        "worlds: site 'ridge' (3 files): corridors model on the DEM /d.tif with 1 mapped line(s) and 0 zone(s)"
    )
