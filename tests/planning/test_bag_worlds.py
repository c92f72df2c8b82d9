"""Tests of ``drd build-dataset --bags FILE...``: each map snapshot of recorded bags is one world.

The bags are written by the tests from the shared helicopter bag messages (``tests/bag_messages.py``); the
helicopter is the small 300 m corridor of the domain tests.
"""

from __future__ import annotations

import json
import shlex
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from bag_messages import SEC, T0, goal_message, obstacles_message, terrain_message

from drd_msgs_py.bags import BagMessage, jazzy_typestore, read_bag, write_bag
from drd_msgs_py.factory import RosbagsMessages
from drd_planner.cli.build_dataset import main
from drd_planner.data.dataset_file import load_dataset
from drd_planner.data.world_sources import FileRecord
from drd_planner.domains.base import domain_from_spec
from drd_planner.exceptions import DatasetError
from drd_planner.planning.bag_plan import maps_until
from drd_planner.planning.bag_worlds import BagWorlds, bag_snapshots

HELI = {"lattice": {"x_range": [0.0, 300.0], "y_range": [-100.0, 100.0], "goal": [300.0, 0.0]}}


@pytest.fixture(scope="module")
def rb() -> RosbagsMessages:
    return RosbagsMessages(jazzy_typestore())


@pytest.fixture(scope="module")
def domain() -> Any:
    return domain_from_spec("helicopter", HELI)


def _maps(rb: RosbagsMessages, offset: int = 0) -> list[BagMessage]:
    """Terrain and obstacles at 0 s, a request at 0.5 s, the obstacles plus a sphere at 1.5 s."""
    t = T0 + offset
    return [
        terrain_message(rb, t),
        obstacles_message(rb, t),
        goal_message(rb, t + SEC // 2, (100.0, 0.0, 40.0)),
        obstacles_message(rb, t + 3 * SEC // 2, extra=True),
    ]


@pytest.fixture(scope="module")
def bag(rb: RosbagsMessages, tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_bag(tmp_path_factory.mktemp("bags") / "maps.mcap", _maps(rb))


def _build(argv: list[str], out: Path) -> int:
    spec = ["--domain", "helicopter", "--domain-spec", json.dumps(HELI), "--seed", "0", "--workers", "1"]
    return main(["build-dataset", *spec, *argv, "--out", str(out)])


def test_each_accepted_map_message_is_one_world(bag: Path, domain: Any) -> None:
    record = FileRecord.of(bag)
    snaps = bag_snapshots(record, frame="map", domain=domain)
    assert [(s.topic, s.time_ns - T0, s.snapshot.version) for s in snaps] == [
        ("/terrain", 0, 1),
        ("/obstacles", 0, 2),
        ("/obstacles", 3 * SEC // 2, 3),
    ]
    assert [len(s.snapshot.obstacles) for s in snaps] == [0, 3, 4]
    assert snaps[1].describe() == {
        "file": "maps.mcap",
        "topic": "/obstacles",
        "time_ns": T0,
        "version": 2,
        "obstacles": 3,
        "terrain": True,
    }


@pytest.mark.slow
def test_a_bag_build_checks_each_snapshot_with_the_scene_checker(
    bag: Path, domain: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "bag.npz"
    assert _build(["--bags", str(bag)], out) == 0
    printed = capsys.readouterr().out.splitlines()
    assert printed[0].startswith(f"wrote {out}: 3 worlds x ")
    assert printed[1] == "worlds: 3 map snapshot(s) of maps.mcap in frame 'map'"
    ds = load_dataset(out)
    messages = read_bag(bag)
    edges = np.arange(ds.graph.num_edges)
    margin = domain.margin
    expected = [
        domain.scene_checker(
            maps_until(messages[:n], T0 + 2 * SEC, frame_id="map", margin=margin).snapshot.scene
        ).check_many(edges)
        for n in (1, 2, 4)
    ]
    assert np.array_equal(ds.X, np.array(expected))
    assert not np.array_equal(ds.X[0], ds.X[1])
    assert ds.world_model == "map_bags"
    assert np.array_equal(ds.world_seeds, [0, 1, 2])
    source = ds.provenance["world_source"]
    assert source["frame"] == "map"
    assert source["files"] == [FileRecord.of(bag).to_json()]
    # The recorded command recreates the bytes, on two processes.
    again = tmp_path / "again.npz"
    assert main([*shlex.split(ds.provenance["command"])[1:], "--workers", "2", "--out", str(again)]) == 0
    assert again.read_bytes() == out.read_bytes()


@pytest.mark.slow
def test_several_bags_in_order_and_the_first_worlds(
    bag: Path, rb: RosbagsMessages, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    second = write_bag(tmp_path / "second.mcap", _maps(rb, offset=10 * SEC)[1:])
    out = tmp_path / "two.npz"
    assert _build(["--bags", str(bag), str(second), "--worlds", "4"], out) == 0
    snapshots = load_dataset(out).provenance["world_source"]["snapshots"]
    assert [(s["file"], s["version"]) for s in snapshots] == [
        ("maps.mcap", 1),
        ("maps.mcap", 2),
        ("maps.mcap", 3),
        ("second.mcap", 1),
    ]
    assert _build(["--bags", str(bag), "--worlds", "9"], tmp_path / "x.npz") == 2
    assert "--worlds 9: the bags hold only 3 map snapshot(s)" in capsys.readouterr().err


def test_refusals_name_the_bag_the_message_and_the_frame(
    bag: Path, rb: RosbagsMessages, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "x.npz"
    empty = write_bag(tmp_path / "goals.mcap", [goal_message(rb, T0, (1.0, 0.0, 40.0))])
    assert _build(["--bags", str(empty)], out) == 2
    err = capsys.readouterr().err
    assert f"bag {empty} has no map snapshot (no accepted obstacles, terrain message)" in err
    moved = [*_maps(rb), obstacles_message(rb, T0 + 2 * SEC, frame="odom")]
    mixed = write_bag(tmp_path / "mixed.mcap", moved)
    assert _build(["--bags", str(mixed)], out) == 2
    err = capsys.readouterr().err
    assert f"bag {mixed}: /obstacles at {T0 + 2 * SEC} ns is refused:" in err
    assert "in frame 'odom'; the planner works in 'map'" in err
    assert "chosen with --frame" in err
    assert _build(["--bags", str(bag), "--frame", "odom"], out) == 2
    assert "/terrain at" in capsys.readouterr().err
    assert not out.exists()


def test_a_bag_that_changed_is_refused_in_the_worker(bag: Path, domain: Any, tmp_path: Path) -> None:
    copy = tmp_path / "copy.mcap"
    copy.write_bytes(bag.read_bytes())
    worlds = BagWorlds([FileRecord.of(copy)], "map")
    assert len(list(worlds.checkers(domain, [0, 2]))) == 2
    with pytest.raises(DatasetError, match="bag world 3 is not among the bags' 3 map snapshots"):
        list(worlds.checkers(domain, [3]))
    copy.write_bytes(bag.read_bytes() + b"\0")
    with pytest.raises(DatasetError, match=r"copy\.mcap changed since the build was planned"):
        list(BagWorlds([FileRecord(str(copy), FileRecord.of(bag).sha256)], "map").checkers(domain, [0]))
