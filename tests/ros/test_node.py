"""The lifecycle node with real rclpy: transitions, maps -> plan, the service, and bad input."""

from __future__ import annotations

import json
import math
import shutil
import signal
import subprocess
import sys
import time
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

rclpy = pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")

from conftest import own_query  # noqa: E402
from geometry_msgs.msg import PoseStamped  # noqa: E402
from harness import Peer, active_planner, private_context, spin_for, spin_until, use_domain  # noqa: E402
from lifecycle_msgs.msg import State  # noqa: E402
from nav_msgs.srv import GetPlan  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.lifecycle import TransitionCallbackReturn  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from sensor_msgs.msg import PointCloud2  # noqa: E402

from drd_msgs_py.factory import RclpyMessages  # noqa: E402
from drd_planner.domains.helicopter import HelicopterDomain  # noqa: E402
from drd_planner.exceptions import UnverifiedPathError  # noqa: E402
from drd_planner.geometry.pose import Pose  # noqa: E402
from drd_planner.geometry.shapes import Box, Sphere  # noqa: E402
from drd_planner.planner import load_prior, load_tree_bundle  # noqa: E402
from drd_planner.planner.anytime import ImproveBudget  # noqa: E402
from drd_planner.planning.map_intake import obstacle_map, terrain_from_cloud  # noqa: E402
from drd_planner.planning.map_state import MapSnapshot  # noqa: E402
from drd_planner.planning.session import QuerySession  # noqa: E402
from drd_planner.planning.world_messages import helicopter_world_messages, obstacle_markers  # noqa: E402
from drd_planner.ros.node import PlannerNode  # noqa: E402
from drd_planner.ros.parameters import parameter_problems, plan_budgets_of  # noqa: E402

TREE = Path(__file__).resolve().parents[2] / "trees" / "heli_wires.npz"
use_domain(60)


@pytest.fixture
def context() -> Iterator[Any]:
    with private_context() as ctx:
        yield ctx


def _node(ctx: Any, trees: list[str], **overrides: Any) -> PlannerNode:
    params = [
        Parameter("prior_paths", value=trees),
        Parameter("start_without_robot_state", value="prior_start"),
        *(Parameter(name, value=value) for name, value in overrides.items()),
    ]
    return PlannerNode(context=ctx, parameter_overrides=params)


def _goal(session: QuerySession, frame: str = "map") -> PoseStamped:
    goal = PoseStamped()
    goal.header.frame_id = frame
    x, y, z = (float(v) for v in session.goal_state[:3])
    goal.pose.position.x, goal.pose.position.y, goal.pose.position.z = x, y, z
    return goal


def test_lifecycle_maps_request_plan_and_service(context: Any) -> None:
    node = _node(context, [str(TREE)])
    peer = Peer(context)
    with active_planner(context, node, peer) as executor:
        session = node.sessions[0]
        domain = session.domain
        assert isinstance(domain, HelicopterDomain)
        markers, cloud = helicopter_world_messages(
            domain.make_world("wires", 3), wire_segments=8, frame_id="map", msgs=RclpyMessages()
        )
        # A request before the maps: a clear error and no plan.
        peer.goals.publish(_goal(session))
        assert spin_until(executor, lambda: any("no maps" in e for e in node.errors))
        assert not peer.plans
        peer.terrain.publish(cloud)
        peer.obstacles.publish(markers)
        assert spin_until(executor, lambda: node.snapshot.version >= 2)
        peer.goals.publish(_goal(session))
        assert spin_until(executor, lambda: bool(peer.plans) and bool(peer.checks))
        plan, log = peer.plans[-1], peer.checks[-1]
        assert plan.header.frame_id == "map"
        assert len(plan.poses) > 2
        last = plan.poses[-1].pose.position
        assert np.allclose([last.x, last.y, last.z], session.goal_state[:3])
        # Every edge of the plan was checked free, and the log equals the offline session on the same maps.

        snapshot = MapSnapshot(
            1,
            obstacle_map(markers, frame_id="map"),
            terrain_from_cloud(cloud, frame_id="map"),
            session.margin,
        )
        offline_session = QuerySession(load_prior(TREE), name="offline")
        offline = offline_session.plan(snapshot, *own_query(offline_session), seed=0)
        assert offline.ok
        assert [s.name for s in log.status] == [f"edge/{c.edge}" for c in offline.checks]
        assert [s.level == b"\x00" for s in log.status] == [c.free for c in offline.checks]
        free = {int(s.name.split("/")[1]) for s in log.status if s.level == b"\x00"}
        assert set(offline.path_edges) <= free
        np.testing.assert_allclose(
            [[p.pose.position.x, p.pose.position.y, p.pose.position.z] for p in plan.poses],
            offline.states[:, :3],
        )
        # The service gives the same path.
        client = peer.node.create_client(GetPlan, "get_plan")
        assert client.wait_for_service(timeout_sec=5.0)
        request = GetPlan.Request()
        request.goal = _goal(session)
        future = client.call_async(request)
        assert spin_until(executor, future.done)
        assert len(future.result().plan.poses) == len(plan.poses)
        assert node.trigger_deactivate() == TransitionCallbackReturn.SUCCESS
        assert node.trigger_cleanup() == TransitionCallbackReturn.SUCCESS


def test_bad_tree_file_fails_configure_and_the_node_stays_up(context: Any, tmp_path: Path) -> None:
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a tree")
    node = _node(context, [str(bad)])
    try:
        assert node.trigger_configure() == TransitionCallbackReturn.FAILURE
        assert any("not a readable prior or tree file" in e for e in node.errors)
        assert node._state_machine.current_state[1] == "unconfigured"
        node.set_parameters([Parameter("prior_paths", value=[str(TREE)])])
        assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS
    finally:
        node.destroy_node()


def _crafted_trees(folder: Path) -> dict[str, Path]:
    """Hostile variants of the shipped prior's tree as a tree file (issue 19 item 7), checksums recomputed
    where they matter."""
    from drd_planner.data.npz_format import array_digest, payload_digest
    from drd_planner.data.tree_file import save_tree

    source = save_tree(folder / "base_tree.npz", load_tree_bundle(TREE))
    with np.load(source, allow_pickle=False) as archive:
        arrays = {k: archive[k] for k in archive.files}
    header = json.loads(arrays.pop("header").tobytes().decode())
    out: dict[str, Path] = {}
    deep = '{"format": "drd_planner.tree", "x": ' + "[" * 100_000 + "]" * 100_000 + "}"
    out["nested"] = folder / "deep.npz"
    np.savez(out["nested"], header=np.frombuffer(deep.encode(), dtype=np.uint8))
    # Library paths cut to their last edge: each ends at the goal, 650 m from the start.
    offsets = arrays["path_offsets"]
    last = arrays["path_edges"][offsets[1:] - 1]
    lib = np.unique(last)
    cols = np.searchsorted(arrays["library_edges"], lib)
    free = np.unpackbits(arrays["world_free_bits"], axis=1, count=arrays["library_edges"].size)
    cut = {k: v for k, v in arrays.items() if k not in ("vertex_paths", "vertex_offsets")}
    cut.update(
        path_edges=last,
        path_offsets=np.arange(last.size + 1, dtype=np.int64),
        library_edges=lib,
        free_fraction=np.ascontiguousarray(arrays["free_fraction"][:, cols]),
        world_free_bits=np.packbits(free[:, cols], axis=1),
    )
    digests = {k: array_digest(k, v) for k, v in cut.items()}
    fields = {**header, "array_sha256": digests}
    fields["payload_sha256"] = payload_digest(digests, fields)
    out["not a walk"] = folder / "single_edges.npz"
    np.savez(out["not a walk"], header=np.frombuffer(json.dumps(fields).encode(), dtype=np.uint8), **cut)
    # Every member flagged as encrypted (zipfile would raise RuntimeError).
    data = bytearray(source.read_bytes())
    with zipfile.ZipFile(source) as zf:
        for info in zf.infolist():
            data[info.header_offset + 6] |= 1
    central = data.index(b"PK\x01\x02")
    while central >= 0:
        data[central + 8] |= 1
        central = data.find(b"PK\x01\x02", central + 4)
    out["encrypted"] = folder / "encrypted.npz"
    out["encrypted"].write_bytes(bytes(data))
    out["is a directory"] = folder / "a_folder"
    out["is a directory"].mkdir()
    return out


class _Warnings:
    """A node's logger that records its warnings (and passes every call on to the real one)."""

    def __init__(self, real: Any) -> None:
        self.real = real
        self.lines: list[str] = []

    def warning(self, text: str, *args: Any, **kwargs: Any) -> Any:
        self.lines.append(text)
        return self.real.warning(text, *args, **kwargs)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.real, name)


def test_the_deprecated_tree_paths_still_loads_and_warns_once_naming_prior_paths(
    context: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    node = PlannerNode(context=context, parameter_overrides=[Parameter("tree_paths", value=[str(TREE)])])
    try:
        logger = _Warnings(node.get_logger())
        monkeypatch.setattr(node, "get_logger", lambda: logger)
        assert node.get_parameter("prior_paths").value == [""]
        assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS, node.errors
        assert [s.name for s in node.sessions] == ["heli_wires"]
        deprecations = [line for line in logger.lines if "deprecated" in line]
        assert len(deprecations) == 1
        assert "tree_paths" in deprecations[0]
        assert "use prior_paths" in deprecations[0]
        assert not node.errors
    finally:
        node.destroy_node()


def test_prior_paths_and_tree_paths_both_set_fail_configure_with_one_error_naming_both(context: Any) -> None:
    overrides = [Parameter("prior_paths", value=[str(TREE)]), Parameter("tree_paths", value=[str(TREE)])]
    node = PlannerNode(context=context, parameter_overrides=overrides)
    try:
        assert node.trigger_configure() == TransitionCallbackReturn.FAILURE
        assert len(node.errors) == 1
        assert "prior_paths and tree_paths are both set" in node.errors[0]
        assert not node.sessions
        assert node._state_machine.current_state[1] == "unconfigured"
        node.set_parameters([Parameter("tree_paths", value=[""])])
        assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS, node.errors
    finally:
        node.destroy_node()


def test_no_prior_named_fails_configure_naming_prior_paths(context: Any) -> None:
    node = PlannerNode(context=context)
    try:
        assert node.trigger_configure() == TransitionCallbackReturn.FAILURE
        assert any("parameter prior_paths names no prior file" in e for e in node.errors)
    finally:
        node.destroy_node()


def test_crafted_tree_files_fail_configure_with_their_reason(context: Any, tmp_path: Path) -> None:
    """Issue 19 item 7: a hostile tree never escapes configure as a traceback; its reason is logged."""
    node = _node(context, [str(TREE)])
    try:
        for reason, path in _crafted_trees(tmp_path).items():
            node.set_parameters([Parameter("prior_paths", value=[str(path)])])
            assert node.trigger_configure() == TransitionCallbackReturn.FAILURE, reason
            assert reason in node.errors[-1], node.errors[-1]
            assert path.name in node.errors[-1], node.errors[-1]
            assert node._state_machine.current_state[1] == "unconfigured"
        node.set_parameters([Parameter("prior_paths", value=[str(TREE)])])
        assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS
    finally:
        node.destroy_node()


def test_bad_requests_and_maps_leave_errors_not_plans(context: Any) -> None:
    node = _node(context, [str(TREE)])
    try:
        assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS
        session = node.sessions[0]
        wrong_frame = _goal(session, frame="odom")
        assert node.plan_for(wrong_frame) is None
        assert "frame 'odom'" in node.errors[-1]
        far = _goal(session)
        far.pose.position.x += 500.0
        # any goal, once maps come
        assert node.plan_for(far) is None
        assert "no maps received yet" in node.errors[-1]
        nan = _goal(session)
        nan.pose.position.z = float("nan")
        assert node.plan_for(nan) is None
        assert "finite" in node.errors[-1]
        cloud = PointCloud2()
        cloud.header.frame_id = "map"
        node._on_map("terrain", cloud)
        assert "terrain refused" in node.errors[-1]
        assert node.snapshot.version == 0
        assert State.PRIMARY_STATE_INACTIVE == node._state_machine.current_state[0]
    finally:
        node.destroy_node()


def _world(session: QuerySession, seed: int = 3) -> tuple[Any, Any]:
    domain = session.domain
    assert isinstance(domain, HelicopterDomain)
    return helicopter_world_messages(
        domain.make_world("wires", seed), wire_segments=8, frame_id="map", msgs=RclpyMessages()
    )


def _publish_world(executor: Any, node: PlannerNode, peer: Peer) -> None:
    """Publish the wires world of the node's first tree and wait until the node holds it."""
    markers, cloud = _world(node.sessions[0])
    peer.terrain.publish(cloud)
    peer.obstacles.publish(markers)
    assert spin_until(executor, lambda: node.snapshot.version >= 2)


def test_a_burst_of_topic_requests_is_answered_or_coalesced(context: Any) -> None:
    node = _node(context, ["heli_wires"])  # a shipped tree by name
    peer = Peer(context)
    with active_planner(context, node, peer) as executor:
        session = node.sessions[0]
        _publish_world(executor, node, peer)
        sent = 8
        for k in range(sent):
            goal = _goal(session)
            goal.header.stamp.sec = k + 1
            peer.goals.publish(goal)

        def served() -> int:
            return sum(1 + int(s["coalesced"]) for s in peer.summaries() if s["request"] == "goal_pose")

        assert spin_until(executor, lambda: served() >= sent)
        spin_for(executor, 0.3)
        summaries = [s for s in peer.summaries() if s["request"] == "goal_pose"]
        assert served() == sent  # every request answered or counted as superseded, none twice
        assert summaries[-1]["request_stamp"] == f"{sent}.000000000"  # the newest one is always served
        assert len(peer.checks) == len(summaries)  # one check log per served request (plan is latched, depth 1)
        assert peer.plans


def test_maps_are_prepared_on_arrival_and_a_bug_in_a_plan_leaves_the_node_planning(
    context: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    node = _node(context, [str(TREE)])
    peer = Peer(context)
    with active_planner(context, node, peer) as executor:
        session = node.sessions[0]
        _publish_world(executor, node, peer)
        # The map callback built the scene and the checker before the snapshot became current.
        assert session.checker(node.snapshot) is session.checker(node.snapshot)
        real_plan = session.plan
        calls: list[int] = []

        def broken_once(*args: Any, **kwargs: Any) -> Any:
            calls.append(1)
            if len(calls) == 1:
                raise ZeroDivisionError("a bug in the planner")
            return real_plan(*args, **kwargs)

        monkeypatch.setattr(session, "plan", broken_once)
        peer.goals.publish(_goal(session))
        assert spin_until(executor, lambda: any("internal error while planning" in e for e in node.errors))
        assert "ZeroDivisionError: a bug in the planner" in node.errors[-1]
        assert not peer.plans
        peer.goals.publish(_goal(session))  # the planning thread is still there
        assert spin_until(executor, lambda: bool(peer.plans) and bool(peer.summaries()))
        summary = peer.summaries()[-1]
        assert summary["result"] == "found"
        assert summary["prior"] == summary["tree"] == "heli_wires"  # tree: deprecated, kept for one release
        assert float(summary["prepare_s"]) < 1e-3
        assert float(summary["plan_messaging_s"]) <= float(summary["messaging_s"])
        assert float(summary["selection_s"]) <= float(summary["policy_s"])


@pytest.mark.slow
def test_planner_node_console_script_autostarts_and_plans(context: Any) -> None:
    beside = Path(sys.executable).parent / "planner_node"  # the venv's scripts, even when not on PATH
    exe = str(beside) if beside.is_file() else shutil.which("planner_node")
    if exe is None:
        pytest.skip("the planner_node console script is not installed (pip install -e ros2_ws/src/drd_planner)")
    args = ["--ros-args", "-p", "prior_paths:=[heli_wires]", "-p", "autostart:=true"]
    args += ["-p", "start_without_robot_state:=prior_start"]
    process = subprocess.Popen([exe, *args], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    peer = Peer(context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(peer.node)
    try:
        session = QuerySession(load_prior(TREE), name="tree")
        markers, cloud = _world(session)
        peer.terrain.publish(cloud)
        peer.obstacles.publish(markers)
        # The node latches onto the maps whenever it comes up (transient_local); then ask until it answers.
        deadline = time.monotonic() + 60.0
        while not peer.plans and time.monotonic() < deadline and process.poll() is None:
            peer.goals.publish(_goal(session))
            spin_until(executor, lambda: bool(peer.plans), timeout=2.0)
        assert peer.plans, "no plan from planner_node"
        last = peer.plans[-1].poses[-1].pose.position
        assert np.allclose([last.x, last.y, last.z], session.goal_state[:3])
    finally:
        process.send_signal(signal.SIGINT)
        try:
            output, _ = process.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            process.kill()
            output, _ = process.communicate()
        executor.shutdown()
        peer.node.destroy_node()
    assert "loaded 1 prior(s): heli_wires" in output
    assert "Traceback" not in output


def test_an_unverified_path_is_logged_with_its_traceback_and_nothing_is_published(
    context: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    node = _node(context, [str(TREE)])
    peer = Peer(context)
    logged: list[str] = []
    real_logger = node.get_logger()

    class _Logger:
        def error(self, text: str) -> None:
            logged.append(text)
            real_logger.error(text)

        def __getattr__(self, name: str) -> Any:
            return getattr(real_logger, name)

    monkeypatch.setattr(node, "get_logger", lambda: _Logger())
    with active_planner(context, node, peer) as executor:
        session = node.sessions[0]
        _publish_world(executor, node, peer)
        real_plan = session.plan
        calls: list[int] = []

        def unverified_once(*args: Any, **kwargs: Any) -> Any:
            calls.append(1)
            if len(calls) == 1:
                raise UnverifiedPathError("edge 3 of the returned path was not checked free")
            return real_plan(*args, **kwargs)

        monkeypatch.setattr(session, "plan", unverified_once)
        peer.goals.publish(_goal(session))
        assert spin_until(executor, lambda: any("UnverifiedPathError" in e for e in node.errors))
        assert "goal_pose: internal error, nothing published" in node.errors[-1]
        assert not any("refused" in e for e in node.errors)  # a bug, never a refused request
        assert not peer.plans
        bug_lines = [line for line in logged if "UnverifiedPathError" in line]
        assert bug_lines
        assert "Traceback (most recent call last)" in bug_lines[-1]
        peer.goals.publish(_goal(session))  # the node is still up and plans
        assert spin_until(executor, lambda: bool(peer.plans))


def test_map_updates_keep_a_plan_they_cannot_block_and_replan_one_they_block(context: Any) -> None:
    node = _node(context, [str(TREE)])
    peer = Peer(context)
    msgs = RclpyMessages()
    with active_planner(context, node, peer) as executor:
        session = node.sessions[0]
        _publish_world(executor, node, peer)
        peer.goals.publish(_goal(session))
        assert spin_until(executor, lambda: bool(peer.plans))
        first = node.published
        assert first is not None
        assert first.ok
        # Far from every plan edge: nothing to re-check, the plan stays, no new plan is published.
        far = Pose(position=(-5000.0, -5000.0, 0.0))
        update = obstacle_markers([("extra/1", Sphere(5.0), far)], frame_id="map", msgs=msgs, delete_all_first=False)
        peer.obstacles.publish(update)
        assert spin_until(executor, lambda: bool(peer.summaries("drd_planner: map update")))
        kept = peer.summaries("drd_planner: map update")[-1]
        assert kept["result"] == "plan_kept"
        assert kept["rechecked"] == "0"
        assert kept["prior"] == "heli_wires"
        assert kept["tree"] == "heli_wires"  # the deprecated key, kept for one release
        assert len(peer.plans) == 1
        assert node.published is first
        # A box on the middle of a plan edge: the plan is blocked, a new one is published and says why.
        edge = first.path_edges[len(first.path_edges) // 2]
        states = session.edge_states(edge)
        middle = Pose(position=tuple(float(v) for v in states[len(states) // 2, :3]))
        update = obstacle_markers(
            [("extra/2", Box((30.0, 30.0, 30.0)), middle)], frame_id="map", msgs=msgs, delete_all_first=False
        )
        peer.obstacles.publish(update)

        def replans() -> list[dict[str, str]]:
            return [s for s in peer.summaries() if s["request"] == "map_update"]

        assert spin_until(executor, lambda: len(peer.plans) >= 2 and bool(replans()) and len(peer.checks) >= 2)
        replanned = replans()[-1]
        assert f"plan edge {edge} blocked" in replanned["replan_reason"]
        second = node.published
        assert second is not None
        assert edge not in second.path_edges
        free = {int(s.name.split("/")[1]) for s in peer.checks[-1].status if s.level == b"\x00"}
        assert set(second.path_edges) <= free  # the new plan was checked free on the new map
        assert second.map_version == node.snapshot.version


def test_a_stated_check_cost_reaches_the_planners_and_its_price_is_measured_at_configure(context: Any) -> None:
    node = _node(context, [str(TREE)], check_cost_ms=0.4)
    peer = Peer(context)
    with active_planner(context, node, peer):
        planner = node.sessions[0].planner
        assert planner.check_cost_ms == 0.4
        measured = planner._models._library_cost_ms  # both prices measured at configure, not in a request
        assert set(measured) == {False, True}
        assert all(library > 0 and own > 0 for library, own in measured.values())
        library, own = measured[True]
        assert planner.lead_checks(joined=True) == math.floor(round(library / (0.4 + own), 9))
        (result,) = node.set_parameters([Parameter("check_cost_ms", value=-1.0)])
        assert not result.successful
        assert "check_cost_ms" in result.reason
    assert "check_cost_ms must be finite" in parameter_problems({"check_cost_ms": math.inf})[0]
    plain = _node(context, [str(TREE)])
    with active_planner(context, plain, Peer(context)):
        assert plain.sessions[0].planner.check_cost_ms is None  # 0, the default: not stated


def test_improve_parameters_publish_a_shorter_verified_path_and_refuse_bad_values(context: Any) -> None:
    """improve_checks > 0: the published plan is the best verified one, no longer than the first path."""
    node = _node(context, [str(TREE)], improve_checks=40)
    peer = Peer(context)
    with active_planner(context, node, peer) as executor:
        session = node.sessions[0]
        assert session.improve_budget == ImproveBudget(checks=40)
        assert session.max_checks is None
        _publish_world(executor, node, peer)  # Wires world 3
        peer.goals.publish(_goal(session))
        assert spin_until(executor, lambda: bool(peer.plans) and bool(peer.summaries()) and bool(peer.checks))
        record = node.history[-1]
        best, summary = record.result, peer.summaries()[-1]
        assert node.published is best
        assert best.ok
        # The first path of the same request, offline on the same maps, without improvement.
        markers, cloud = _world(session)
        snapshot = MapSnapshot(
            1,
            obstacle_map(markers, frame_id="map"),
            terrain_from_cloud(cloud, frame_id="map"),
            session.margin,
        )
        start, goal = int(session.domain.start), int(session.domain.goal)
        first = QuerySession(session.prior, name="first").plan(snapshot, start, goal, seed=0)
        assert first.ok
        assert best.first_cost == pytest.approx(first.cost)
        assert best.cost < first.cost  # measured: 739.29 -> 700.0 m, 1 shorter path, 24 checks
        assert best.improvements >= 1
        assert best.stage == "improve"
        assert summary["improvements"] == str(best.improvements)
        assert summary["improve_stop"] == best.improve_stop
        assert int(summary["improve_checks"]) == len(best.checks) - len(first.checks) > 0
        assert f"improvement stopped: {best.improve_stop}" in summary["message"]
        # What is on `plan` is that path, and every edge of it was checked free in the published log.
        np.testing.assert_allclose(
            [[p.pose.position.x, p.pose.position.y, p.pose.position.z] for p in peer.plans[-1].poses],
            best.states[:, :3],
        )
        free = {int(s.name.split("/")[1]) for s in peer.checks[-1].status if s.level == b"\x00"}
        assert set(best.path_edges) <= free
        # A map update that blocks the improved path: re-checked, replanned (improving again) on the new map.
        edge = best.path_edges[len(best.path_edges) // 2]
        peer.block_edge(session, edge)
        assert spin_until(executor, lambda: len(peer.plans) >= 2 and len(peer.checks) >= 2)
        assert spin_until(executor, lambda: peer.summaries()[-1]["request"] == "map_update")
        again, summary = node.published, peer.summaries()[-1]
        assert again is not None
        assert again is node.history[-1].result
        assert edge not in again.path_edges
        assert f"plan edge {edge} blocked" in summary["replan_reason"]
        assert summary["improve_stop"]
        free = {int(s.name.split("/")[1]) for s in peer.checks[-1].status if s.level == b"\x00"}
        assert set(again.path_edges) <= free
        assert again.map_version == node.snapshot.version
        # A negative value is refused with its name; the old value stays.
        for name, bad in (("improve_checks", -1), ("improve_time_budget", -1.0)):
            (result,) = node.set_parameters([Parameter(name, value=bad)])
            assert not result.successful
            assert name in result.reason
        assert node.get_parameter("improve_checks").value == 40
        assert node.get_parameter("improve_time_budget").value == 0.0
    assert parameter_problems({"improve_checks": -1}) == ["improve_checks must be >= 0, got -1"]
    assert "improve_time_budget must be finite" in parameter_problems({"improve_time_budget": math.nan})[0]
    # Either parameter enables the improvement; 0 is no limit; both 0 is off.
    assert plan_budgets_of({"improve_checks": 0, "improve_time_budget": 0.0})["improve_budget"] is None
    assert plan_budgets_of({"improve_time_budget": 0.5})["improve_budget"] == ImproveBudget(seconds=0.5)
    assert plan_budgets_of({"improve_checks": 7, "max_checks": 50}) == {
        "max_checks": 50,
        "time_budget_s": None,
        "improve_budget": ImproveBudget(checks=7),
    }
    with pytest.raises(rclpy.exceptions.ParameterException):  # the descriptor's range, before the node exists
        _node(context, [str(TREE)], improve_checks=-1)
