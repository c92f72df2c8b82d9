"""Tests of the world-source seam: file records, source requests, the registry and the worker cache."""

from __future__ import annotations

import hashlib
import json
import os
import shlex
from pathlib import Path

import pytest
from test_dataset_builder import GridDomain

from drd_planner.data.dataset_options import ALL_WORLDS, DatasetRecipe
from drd_planner.data.world_sources import (
    SOURCE_MODULES,
    FileRecord,
    MapBags,
    SceneFolder,
    SiteFile,
    SourceCache,
    TerrainFile,
    online_domain,
    open_world_set,
    records_from_json,
)
from drd_planner.exceptions import DatasetError


def test_a_file_record_hashes_the_bytes_and_refuses_a_changed_file(tmp_path: Path) -> None:
    path = tmp_path / "scene0001.yaml"
    path.write_bytes(b"world: {collision_objects: []}\n")
    record = FileRecord.of(path)
    assert record.path == str(path)
    assert record.sha256 == hashlib.sha256(path.read_bytes()).hexdigest()
    assert record.read() == path.read_bytes()
    assert FileRecord.from_json(json.loads(json.dumps(record.to_json()))) == record
    path.write_bytes(b"world: {collision_objects: [changed]}\n")
    with pytest.raises(DatasetError, match=rf"{path} changed since the build was planned \(SHA-256 "):
        record.read()
    path.unlink()
    with pytest.raises(DatasetError, match=f"cannot read {path}"):
        record.read()
    with pytest.raises(DatasetError, match=f"cannot read scene file {path}"):
        FileRecord.of(path, what="scene file")


def test_file_records_are_made_absolute(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (tmp_path / "a.asc").write_text("x")
    monkeypatch.chdir(tmp_path)
    assert FileRecord.of("a.asc").path == str(tmp_path / "a.asc")
    assert TerrainFile("a.asc").path == str(tmp_path / "a.asc")
    assert SceneFolder("sub/../scenes").folder == os.path.join(str(tmp_path), "scenes")


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"path": 1, "sha256": "0" * 64}, "needs 'path' and 'sha256' strings"),
        ({"path": "a", "sha256": "abc"}, "needs a 64-digit 'sha256'"),
    ],
)
def test_malformed_records_are_refused(data: dict[str, object], message: str) -> None:
    with pytest.raises(DatasetError, match=message):
        FileRecord.from_json(data)
    with pytest.raises(DatasetError, match="needs a list 'files'"):
        records_from_json({"files": "a"})


def test_source_requests_give_their_flags_back() -> None:
    assert SceneFolder("/d").argv() == ["--scenes", "/d"]
    assert SceneFolder("/d", requests=False).argv() == ["--scenes", "/d", "--no-requests"]
    assert MapBags(("/a.mcap", "/b.mcap"), frame="map").argv() == [
        "--bags",
        "/a.mcap",
        "/b.mcap",
        "--frame",
        "map",
    ]
    terrain = TerrainFile("/t.asc", site=(1.5, 2.0), site_jitter=30.0, crop="as-is", crop_scale=(10.0, 20.0))
    assert terrain.argv() == [
        "--terrain",
        "/t.asc",
        "--site=1.5,2.0",
        "--site-jitter",
        "30.0",
        "--crop",
        "as-is",
        "--crop-scale",
        "10.0,20.0",
    ]
    with pytest.raises(DatasetError, match="--bags needs at least one bag file"):
        MapBags(())
    with pytest.raises(DatasetError, match="--crop must be one of random, as-is"):
        TerrainFile("/t.asc", crop="tilted")


def test_recipes_with_a_source_name_their_world_model_and_command() -> None:
    recipe = DatasetRecipe("arm", "", ALL_WORLDS, 0, source=SceneFolder("/s"), domain_spec={"k": 4})
    assert recipe.world_model == "moveit_scenes"
    assert recipe.num_worlds == ALL_WORLDS
    argv = shlex.split(recipe.command())
    assert argv[:6] == ["drd", "build-dataset", "--domain", "arm", "--scenes", "/s"]
    assert "--worlds" not in argv
    assert "--world-model" not in argv
    assert argv[argv.index("--domain-spec") + 1] == '{"k": 4}'
    first = DatasetRecipe("helicopter", "", 7, 1, source=TerrainFile("/t.asc"))
    assert first.world_model == "terrain"
    assert shlex.split(first.command())[4:8] == [
        "--terrain",
        "/t.asc",
        "--worlds",
        "7",
    ]
    with pytest.raises(DatasetError, match="--scenes takes its worlds from files: leave out --world-model clutter"):
        DatasetRecipe("arm", "clutter", 3, 0, source=SceneFolder("/s"))
    with pytest.raises(DatasetError, match="num_worlds must be a positive integer"):
        DatasetRecipe("arm", "clutter", ALL_WORLDS, 0)


def test_the_registry_names_a_module_per_kind() -> None:
    assert set(SOURCE_MODULES) == {SceneFolder.kind, MapBags.kind, TerrainFile.kind, SiteFile.kind}
    with pytest.raises(DatasetError, match="unknown world source 'tape'; known: scenes, terrain, site, bags"):
        open_world_set({"kind": "tape"})


def test_the_process_cache_opens_a_source_once(tmp_path: Path) -> None:
    path = tmp_path / "scene0001.yaml"
    path.write_text("world: {collision_objects: []}\n")
    text = json.dumps({"kind": "scenes", "files": [FileRecord.of(path).to_json()]}, sort_keys=True)
    cache = SourceCache()
    first = cache.worlds(text)
    assert cache.worlds(text) is first
    other = json.dumps({"kind": "scenes", "files": []})
    assert cache.worlds(other) is not first


def test_file_worlds_need_an_online_domain() -> None:
    with pytest.raises(DatasetError, match=r"--scenes needs a domain with scene checks .* domain 'grid_test'"):
        online_domain(GridDomain(), "--scenes")
