"""``drd plan --bag``: the check log on the maps at a bag's request, and its errors."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO_ROOT

from drd_msgs_py.bags import BagMessage, read_bag, write_bag
from drd_planner.cli.main import main
from drd_planner.planner import load_prior
from drd_planner.planning.bag_plan import plan_bag_request
from drd_planner.planning.session import QuerySession

BAG = REPO_ROOT / "bags" / "heli_wires.mcap"
TREE = REPO_ROOT / "trees" / "heli_wires.npz"
CHECK = re.compile(r"^  check +(\d+): edge +(\d+) \((\d+)->(\d+)\) +(free|BLOCKED) +\[(\w+)\]$")


@pytest.fixture(scope="module")
def bag() -> Path:
    if not BAG.is_file():
        pytest.skip(f"{BAG} not generated (python scripts/tools/make_bags.py)")
    return BAG


def _log(out: str) -> list[tuple[int, bool, str]]:
    rows = [CHECK.match(line) for line in out.splitlines()]
    return [(int(m[2]), m[5] == "free", m[6]) for m in rows if m]


def _error(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith("drd: error:"), err
    return err[0]


@pytest.mark.parametrize("request_index", [0, 1, 2, 3])
def test_plan_bag_prints_the_offline_check_log_and_path(
    bag: Path, request_index: int, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["plan", "--bag", str(bag), "--tree", str(TREE), "--request", str(request_index)]) == 0
    out = capsys.readouterr().out
    session = QuerySession(load_prior(TREE), name="offline")
    planned = plan_bag_request(session, read_bag(bag), request_index, frame="map", seed=0)
    want, request = planned.result, planned.request
    assert _log(out) == [(c.edge, c.free, c.stage) for c in want.checks]
    assert f"request {request_index} (goal_pose at +{(request.time_ns - read_bag(bag)[0].time_ns) / 1e9:.2f} s)" in out
    assert f"path edges: {list(want.path_edges)}" in out
    assert f"verified free after {len(want.checks)} checks [query {want.query}, stage {want.stage}]" in out
    num_vertices = session.prior.graph.num_vertices
    vertex_rows = [line.split() for line in out.splitlines() if re.match(r"^ +(\d+|state): ", line)]
    labels = [r[0].rstrip(":") for r in vertex_rows]
    assert labels == [str(v) if v < num_vertices else "state" for v in want.path_vertices]
    states = np.array([[float(v) for v in r[1:]] for r in vertex_rows])
    on_graph = [k for k, v in enumerate(want.path_vertices) if v < num_vertices]
    np.testing.assert_allclose(
        states[on_graph], [session.vertex_state(want.path_vertices[k]) for k in on_graph], atol=5e-4
    )
    # The path starts where the robot reported itself (odometry) before the request.
    np.testing.assert_allclose(states[0][:3], np.asarray(planned.start)[:3], atol=5e-4)


def test_the_update_changes_the_plan(bag: Path, capsys: pytest.CaptureFixture[str]) -> None:
    logs = []
    for k in (0, 1):
        assert main(["plan", "--bag", str(bag), "--tree", str(TREE), "--request", str(k)]) == 0
        out = capsys.readouterr().out
        logs.append(_log(out))
        assert f"version {2 if k == 0 else 3}" in out
    assert logs[0] != logs[1]
    blocked_later = {edge for edge, free, _ in logs[1] if not free}
    free_first = {edge for edge, free, _ in logs[0] if free}
    assert blocked_later & free_first, "the obstacle added at 1.5 s blocks an edge that was free at request 0"


def test_plan_bag_errors_are_one_line(bag: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["plan", "--bag", str(bag), "--tree", str(TREE), "--request", "4"]) == 2
    assert "it has 4 request(s)" in _error(capsys)
    assert main(["plan", "--bag", str(tmp_path / "none.mcap"), "--tree", str(TREE)]) == 2
    assert "none.mcap" in _error(capsys)
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(bytes(range(256)) * 4)
    assert main(["plan", "--bag", str(junk), "--tree", str(TREE)]) == 2
    assert "not a readable rosbag2 MCAP bag" in _error(capsys)
    assert main(["plan", "--bag", str(bag), "--tree", str(TREE), "--world", "3"]) == 2
    assert "--request" in _error(capsys)
    assert main(["plan", "--bag", str(bag), "--tree", str(TREE), "--frame", "odom"]) == 2
    assert "frame 'map'" in _error(capsys)  # the request is in map; the maps were refused too
    # A request whose goal lies outside the lattice's extent.
    messages = read_bag(bag)
    far = []
    for m in messages:
        if m.topic == "/goal_pose":
            m.message.pose.position.x += 400.0
        far.append(BagMessage(m.topic, m.msgtype, m.time_ns, m.message))
    moved = write_bag(tmp_path / "far.mcap", far)
    assert main(["plan", "--bag", str(moved), "--tree", str(TREE)]) == 2
    assert "goal position (1100.0, 0.0) m is outside the lattice's horizontal extent x [0, 700] m" in _error(capsys)
    # No robot state before the request: an error, or the prior's start with --prior-start.
    stateless = write_bag(tmp_path / "stateless.mcap", [m for m in read_bag(bag) if m.topic != "/odom"])
    assert main(["plan", "--bag", str(stateless), "--tree", str(TREE)]) == 2
    assert "no accepted odom message" in _error(capsys)
    assert main(["plan", "--bag", str(stateless), "--tree", str(TREE), "--prior-start"]) == 0
    assert "from vertex 0 to vertex 730" in capsys.readouterr().out


def test_world_is_still_required_for_datasets(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    assert main(["plan", "--dataset", str(tmp_path / "d.npz"), "--tree", str(TREE)]) == 2
    assert "--world is required" in _error(capsys)


def test_a_corrupt_map_message_stops_the_plan_unless_asked_to_plan_as_the_node(
    bag: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 33 item 6: 4,000 flipped bytes inside the terrain message planned and exited 0 without a word."""
    rng = np.random.default_rng(6)
    corrupt = []
    for m in read_bag(bag):
        if m.topic.endswith("terrain"):
            data = np.array(m.message.data, dtype=np.uint8)
            where = rng.choice(data.size, size=min(4000, data.size), replace=False)
            data[where] ^= 0xFF
            m.message.data = data
        corrupt.append(BagMessage(m.topic, m.msgtype, m.time_ns, m.message))
    broken = write_bag(tmp_path / "corrupt.mcap", corrupt)
    assert main(["plan", "--bag", str(broken), "--tree", str(TREE)]) == 2
    err = _error(capsys)
    assert "terrain at" in err
    assert "refused" in err
    assert "--skip-refused-maps" in err
    assert main(["plan", "--bag", str(broken), "--tree", str(TREE), "--skip-refused-maps"]) in (0, 1)
    out = capsys.readouterr().out
    # which maps it planned on, and why
    assert "terrain none" in out
    assert "  refused: terrain at" in out
