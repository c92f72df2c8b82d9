"""Bag replay end to end with real rclpy: the bundled bags into a real PlannerNode, outputs recorded.

For each request of the bag: a plan was published; its check log (edge ids and outcomes, in order)
equals the offline plan of that request (:func:`drd_planner.planning.bag_plan.plan_bag_request`: the
maps decoded from the bag at that request, from the robot's state in the bag, same seed); every edge
of the plan was checked free in that log; the recorded bag reads back with rosbags. The requests go
to the stored goal twice (a precomputed tree), then from where the robot has moved to a new goal (a
library and tree built online) and from between two vertices (joined by a new motion).
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import REPO_ROOT, SHARED_DATA

rclpy = pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")

from rclpy.parameter import Parameter  # noqa: E402

from drd_msgs_py.bags import BagMessage, bag_requests, open_bag, read_bag  # noqa: E402
from drd_planner.cli.replay import main  # noqa: E402
from drd_planner.planner import load_prior  # noqa: E402
from drd_planner.planning.bag_plan import plan_bag_request  # noqa: E402
from drd_planner.planning.session import QuerySession  # noqa: E402
from drd_planner.planning.session_plan import SessionPlan  # noqa: E402
from drd_planner.ros.node import PlannerNode  # noqa: E402
from drd_planner.ros.replay import ReplayOptions, ReplaySummary, replay_bag  # noqa: E402

pytestmark = pytest.mark.slow  # nodes in child processes; several seconds each

os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
os.environ["ROS_DOMAIN_ID"] = str(110 + os.getpid() % 20)

BAGS = REPO_ROOT / "bags"
TREES = REPO_ROOT / "trees"


def _ok(status: Any) -> bool:
    """Level OK (0): rosbags decodes the ``byte`` level as an int, rclpy as bytes."""
    level = status.level
    return (level[0] if isinstance(level, bytes) else int(level)) == 0


@pytest.fixture
def context() -> Iterator[Any]:
    ctx = rclpy.context.Context()
    rclpy.init(context=ctx)
    yield ctx
    ctx.try_shutdown()


def _replay(ctx: Any, tree: str, frame: str, bag: Path, out: Path) -> tuple[ReplaySummary, PlannerNode]:
    if not bag.is_file():
        pytest.skip(f"{bag} not generated (python scripts/tools/make_bags.py)")
    params = [
        Parameter("prior_paths", value=[str(TREES / tree)]),
        Parameter("frame_id", value=frame),
    ]
    node = PlannerNode(context=ctx, parameter_overrides=params)
    try:
        assert node.trigger_configure().name == "SUCCESS", node.errors
        assert node.trigger_activate().name == "SUCCESS"
        # Stepped by events (each message once the node took the ones before and answered: on a loaded
        # machine a request sent by the clock alone was coalesced with the next), then until it answered.
        options = ReplayOptions(
            record=out,
            settle=1.0,
            settle_until=lambda: node.planning_idle,
            ready=lambda published: node.inputs_taken >= published and node.planning_idle,
        )
        summary = replay_bag(bag, context=ctx, nodes=[node], options=options)
    except BaseException:
        node.destroy_node()
        raise
    return summary, node


def _response(recorded: list[BagMessage], after_ns: int, before_ns: int) -> BagMessage:
    """The first recorded message in [after_ns, before_ns)."""
    hits = [m for m in recorded if after_ns <= m.time_ns < before_ns]
    assert hits, f"nothing recorded between {after_ns} and {before_ns}"
    return hits[0]


def _check_requests(summary: ReplaySummary, bag: Path, out: Path, tree: str, frame: str) -> list[SessionPlan]:
    """The assertions of the module docstring for every request; the offline results."""
    messages = read_bag(bag)
    requests = bag_requests(messages)
    assert len(requests) == 4
    assert summary.published_per_topic == {t.name: t.count for t in open_bag(bag).topics.values()}
    assert not summary.unmatched
    # The recorded bag reads back with rosbags and holds what the replay received.
    recorded = read_bag(out)
    assert {t: n for t, n in summary.recorded_per_topic.items()} == {
        t.name: t.count for t in open_bag(out).topics.values()
    }
    by_topic: dict[str, list[BagMessage]] = {}
    for m in recorded:
        by_topic.setdefault(m.topic, []).append(m)
    assert open_bag(out).topics["/plan"].qos[0].durability.name == "TRANSIENT_LOCAL"
    # When each request really went out, on the bag's timeline (the recorder's clock).
    sent = [p.sent_ns for p in summary.published if p.topic.endswith(("goal_pose", "goal_joints"))]
    assert len(sent) == len(requests)
    session = QuerySession(load_prior(TREES / tree), name="offline")
    results, starts = [], []
    for k, request in enumerate(requests):
        planned = plan_bag_request(session, messages, request.index, frame=frame, seed=0)
        offline = planned.result
        starts.append(planned.start)
        assert offline.ok, offline.message
        results.append(offline)
        until = sent[k + 1] if k + 1 < len(sent) else 2**63
        log = _response(by_topic["/edge_checks"], sent[k], until).message
        assert [s.name for s in log.status] == [f"edge/{c.edge}" for c in offline.checks]
        assert [_ok(s) for s in log.status] == [c.free for c in offline.checks]
        free = {int(s.name.split("/")[1]) for s in log.status if _ok(s)}
        assert set(offline.path_edges) <= free, "every plan edge was checked free for this request"
        plan = _response(by_topic["/plan"], sent[k], until).message
        assert plan.header.frame_id == frame
        assert len(plan.poses) >= 2
        if session.domain.publishes_joint_trajectory:
            trajectory = _response(by_topic["/joint_trajectory"], sent[k], until).message
            got = np.array([p.positions for p in trajectory.points])
            np.testing.assert_allclose(got, offline.states, atol=1e-9)
        else:
            got = np.array([[p.pose.position.x, p.pose.position.y, p.pose.position.z] for p in plan.poses])
            np.testing.assert_allclose(got, offline.states[:, :3], atol=1e-9)
        summaries = [
            {kv.key: kv.value for kv in s.values}
            for m in by_topic["/diagnostics"]
            if sent[k] <= m.time_ns < until
            for s in m.message.status
        ]
        assert any(
            v.get("result") == "found"
            and v.get("checks") == str(len(offline.checks))
            and v.get("query") == offline.query
            for v in summaries
        )
    # The update between the first two requests blocked an edge of the first plan; the second avoids it.
    first, second = results[:2]
    blocked_later = {c.edge for c in second.checks if not c.free}
    assert blocked_later & set(first.path_edges)
    assert not blocked_later & set(second.path_edges)
    # Then the robot moves: a goal no tree was built for, and a start between two vertices.
    assert [r.query for r in results] == [first.query, first.query, "online", "connected"]
    assert first.query.startswith("tree:")
    num_vertices = session.prior.graph.num_vertices
    assert results[2].path_vertices[0] < num_vertices <= results[3].path_vertices[0]  # a new start state
    for k in (2, 3):  # each starts where the robot last reported itself before the request
        reported = np.asarray(starts[k], dtype=float)
        np.testing.assert_allclose(results[k].states[0][: reported.size], reported, atol=1e-6)
    return results


@pytest.mark.parametrize("name", ["heli_wires", "heli_lines"])
def test_heli_bag_replays_into_the_node_and_matches_drd_plan(name: str, context: Any, tmp_path: Path) -> None:
    out = tmp_path / "heli_out.mcap"
    summary, node = _replay(context, f"{name}.npz", "map", BAGS / f"{name}.mcap", out)
    try:
        _check_requests(summary, BAGS / f"{name}.mcap", out, f"{name}.npz", "map")
        assert summary.record_path == out
        assert not summary.interrupted
        assert not node.errors, node.errors
    finally:
        node.destroy_node()


def test_replaying_a_bag_twice_gives_identical_check_logs(context: Any, tmp_path: Path) -> None:
    logs = []
    for k in range(2):
        out = tmp_path / f"run{k}.mcap"
        _, node = _replay(context, "heli_wires.npz", "map", BAGS / "heli_wires.mcap", out)
        node.destroy_node()
        checks = [m.message for m in read_bag(out) if m.topic == "/edge_checks"]
        logs.append([[(s.name, _ok(s)) for s in log.status] for log in checks])
    # four requests and the replan after the update, each checked
    assert len(logs[0]) == 5
    assert all(logs[0])
    assert logs[0] == logs[1]


def test_arm_bag_replays_into_the_node_and_matches_drd_plan(context: Any, tmp_path: Path) -> None:
    if not (SHARED_DATA / "panda" / "panda.urdf").is_file():
        pytest.skip("the shared Panda files are needed for the arm tree")
    out = tmp_path / "arm_out.mcap"
    bag = BAGS / "arm_table_clutter.mcap"
    summary, node = _replay(context, "arm_table_clutter.npz", "panda_link0", bag, out)
    try:
        _check_requests(summary, bag, out, "arm_table_clutter.npz", "panda_link0")
        assert not node.errors, node.errors
    finally:
        node.destroy_node()


def test_a_stepped_replay_waits_until_the_node_took_each_message_and_answered(context: Any, tmp_path: Path) -> None:
    """Issue 31 (3): at 50x speed every request still follows its maps and the previous answer."""
    bag = BAGS / "heli_wires.mcap"
    if not bag.is_file():
        pytest.skip(f"{bag} not generated")
    params = [
        Parameter("prior_paths", value=[str(TREES / "heli_wires.npz")]),
        Parameter("frame_id", value="map"),
    ]
    node = PlannerNode(context=context, parameter_overrides=params)
    asked: list[tuple[int, int, bool]] = []

    def ready(published: int) -> bool:
        asked.append((published, node.inputs_taken, node.planning_idle))
        return node.inputs_taken >= published and node.planning_idle

    try:
        assert node.trigger_configure().name == "SUCCESS"
        assert node.trigger_activate().name == "SUCCESS"
        options = ReplayOptions(
            record=tmp_path / "o.mcap", rate=50.0, settle_until=lambda: node.planning_idle, ready=ready
        )
        summary = replay_bag(bag, context=context, nodes=[node], options=options)
        assert len(summary.published) == 10
        assert node.inputs_taken == 10
        # Every message after the first went out only once the node had taken all before it and was idle.
        last = {n: (taken, idle) for n, taken, idle in asked}
        assert sorted(last) == list(range(1, 10))
        assert all(taken >= n and idle for n, (taken, idle) in last.items())
        # The story in order: the four requests and the replan after the blocking update, each planned.
        logs = [m.message for m in read_bag(tmp_path / "o.mcap") if m.topic == "/edge_checks"]
        assert len(logs) == 5
        assert all(log.status for log in logs)
    finally:
        node.destroy_node()


def test_replay_without_a_planner_records_nothing(context: Any, tmp_path: Path) -> None:
    bag = BAGS / "heli_wires.mcap"
    if not bag.is_file():
        pytest.skip(f"{bag} not generated")
    lines: list[str] = []
    options = ReplayOptions(record=tmp_path / "o.mcap", rate=10.0, settle=0.1, wait=0.2, log=lines.append)
    summary = replay_bag(bag, context=context, options=options)
    assert len(summary.published) == 10
    assert not summary.recorded
    assert set(summary.unmatched) == {"/terrain", "/obstacles", "/odom", "/goal_pose"}
    assert summary.seconds < 5.0  # 5.5 s of bag at rate 10
    assert any("no subscriber on /goal_pose" in line for line in lines)
    assert read_bag(tmp_path / "o.mcap") == []
    with pytest.raises(ValueError, match="rate"):
        replay_bag(bag, context=context, options=ReplayOptions(rate=0.0))
    with pytest.raises(ValueError, match="settle_limit"):
        ReplayOptions(settle_limit=float("nan"))


def test_cli_errors_are_one_line_and_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"\x89MCAP0\r\n" + bytes(200))
    exists = tmp_path / "exists.mcap"
    exists.write_bytes(b"")
    cases = [
        ([str(tmp_path / "missing.mcap")], "missing.mcap"),
        ([str(junk)], "not a readable rosbag2 MCAP bag"),
    ]
    if (BAGS / "heli_wires.mcap").is_file():
        cases.append(([str(BAGS / "heli_wires.mcap"), "--record", str(exists)], "exists already"))
    for argv, text in cases:
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1, err
        assert err[0].startswith("drd_replay: error:"), err
        assert text in err[0], err


def test_cli_without_a_running_planner_exits_2_and_writes_no_bag(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    bag = BAGS / "heli_wires.mcap"
    if not bag.is_file():
        pytest.skip(f"{bag} not generated")
    monkeypatch.setenv("ROS_DOMAIN_ID", str(200 + os.getpid() % 30))  # a domain no planner is on
    out = tmp_path / "out.mcap"
    assert main([str(bag), "--record", str(out), "--wait", "0.5", "--rate", "10"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert "no node subscribes to any of the bag's topics" in err[0], err
    assert not out.exists()
