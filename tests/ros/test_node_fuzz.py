# mypy: allow-untyped-calls
"""Bad input against the real node over DDS: thousands of seeded malformed messages, one at a time.

For every message the peer waits until the node either refused it (an error on ``/diagnostics``) or
accepted it (a new map snapshot, or a plan summary for a request). Checked: the executor never raised,
each malformed message gave exactly one one-line error naming the topic and the reason, a refused
map left the node's snapshot untouched (the same object), nothing the interface requires to be
refused was accepted, every published plan consists only of edges the matching ``edge_checks``
reported free, and at the end the node still serves a valid request with the offline session's plan.
"""

from __future__ import annotations

import os
import time
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest

rclpy = pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")

import malformed as mf  # noqa: E402
from conftest import own_query  # noqa: E402
from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
from geometry_msgs.msg import PoseStamped  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from nav_msgs.msg import Path as PathMsg  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.lifecycle import TransitionCallbackReturn  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402
from sensor_msgs.msg import JointState, PointCloud2  # noqa: E402
from std_msgs.msg import String  # noqa: E402
from trajectory_msgs.msg import JointTrajectory  # noqa: E402
from visualization_msgs.msg import MarkerArray  # noqa: E402

import drd_planner.ros.node as node_module  # noqa: E402
from drd_msgs_py.exceptions import MessageError  # noqa: E402
from drd_planner.exceptions import DrdError  # noqa: E402
from drd_planner.planner import load_prior  # noqa: E402
from drd_planner.planning.map_intake import obstacle_map, terrain_from_cloud  # noqa: E402
from drd_planner.planning.map_state import MapSnapshot  # noqa: E402
from drd_planner.planning.map_store import MapStore  # noqa: E402
from drd_planner.planning.session import QuerySession  # noqa: E402
from drd_planner.ros.node import LATCHED, REQUESTS, PlannerNode  # noqa: E402

pytestmark = pytest.mark.slow  # nodes in child processes; several seconds each

ROOT = Path(__file__).resolve().parents[2]
HELI_TREE = ROOT / "trees" / "heli_wires.npz"
ARM_TREE = ROOT / "trees" / "arm_table_clutter.npz"
PANDA_URDF = ROOT.parent / "shared" / "data" / "panda" / "panda.urdf"
DOMAIN_ID = 170 + os.getpid() % 20
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ["ROS_DOMAIN_ID"] = str(DOMAIN_ID)

#: Subscriber side of the planner's outputs: deep enough that nothing is lost while the peer is busy.
RECORD = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
RECORD_LATCHED = QoSProfile(
    depth=1000, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)
#: Seconds to wait for the node's answer to one message before calling it lost.
ANSWER_TIMEOUT = 5.0
TRACEBACK_MARKS = ("Traceback (most recent call last)", 'File "', "raise ")


@pytest.fixture
def context() -> Iterator[Any]:
    ctx = rclpy.context.Context()
    rclpy.init(context=ctx, domain_id=DOMAIN_ID)
    yield ctx
    ctx.try_shutdown()


def _stamp(msg: Any) -> tuple[int, int]:
    return int(msg.header.stamp.sec), int(msg.header.stamp.nanosec)


def _values(status: Any) -> dict[str, str]:
    return {str(kv.key): str(kv.value) for kv in status.values}


def _is_error_report(status: Any) -> bool:
    """An error the node reported (bad message or request), as opposed to a plan summary."""
    return status.level == b"\x02" and "result" not in _values(status)


@dataclass
class _Peer:
    """The other side: publishes inputs, records the planner's outputs."""

    node: Any
    publishers: dict[str, Any] = field(default_factory=dict)
    statuses: list[tuple[tuple[int, int], Any]] = field(default_factory=list)
    plans: list[Any] = field(default_factory=list)
    trajectories: list[Any] = field(default_factory=list)
    checks: dict[tuple[int, int], Any] = field(default_factory=dict)

    @classmethod
    def create(cls, ctx: Any) -> _Peer:
        peer = cls(rclpy.create_node("fuzz_peer", context=ctx))
        n = peer.node
        peer.publishers = {
            "obstacles": n.create_publisher(MarkerArray, "obstacles", LATCHED),
            "terrain": n.create_publisher(PointCloud2, "terrain", LATCHED),
            "robot_description": n.create_publisher(String, "robot_description", LATCHED),
            "goal_pose": n.create_publisher(PoseStamped, "goal_pose", REQUESTS),
            "goal_joints": n.create_publisher(JointState, "goal_joints", REQUESTS),
            "odom": n.create_publisher(Odometry, "odom", REQUESTS),
        }
        n.create_subscription(DiagnosticArray, "/diagnostics", peer._on_diagnostics, RECORD)
        n.create_subscription(DiagnosticArray, "edge_checks", peer._on_checks, RECORD)
        n.create_subscription(PathMsg, "plan", peer.plans.append, RECORD_LATCHED)
        n.create_subscription(JointTrajectory, "joint_trajectory", peer.trajectories.append, RECORD_LATCHED)
        return peer

    def _on_diagnostics(self, msg: Any) -> None:
        self.statuses.extend((_stamp(msg), s) for s in msg.status)

    def _on_checks(self, msg: Any) -> None:
        self.checks[_stamp(msg)] = msg

    def error_reports(self, since: int = 0) -> list[Any]:
        return [s for _, s in self.statuses[since:] if _is_error_report(s)]

    def summaries(self, since: int = 0, request: str | None = None) -> list[Any]:
        """Plan summaries since ``since``; with ``request``, those that answer that request topic."""
        out = [s for _, s in self.statuses[since:] if "result" in _values(s)]  # not heartbeats or map reports
        if request is not None:
            out = [s for s in out if _values(s).get("request", request) == request]
        return out


def _spin_until(executor: Any, done: Callable[[], bool], timeout: float) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        executor.spin_once(timeout_sec=0.02)
        if done():
            return True
    return False


@dataclass
class _Tally:
    """What happened to the cases of one run."""

    refused: Counter[str] = field(default_factory=Counter)
    accepted: Counter[str] = field(default_factory=Counter)
    #: Error reports that followed an accepted message (a re-check that withdrew the published plan).
    followups: int = 0
    problems: list[str] = field(default_factory=list)

    def problem(self, text: str) -> None:
        if len(self.problems) < 30:
            self.problems.append(text)


def _feed(executor: Any, node: PlannerNode, peer: _Peer, cases: list[mf.Case]) -> _Tally:
    """Publish each case and wait for the node's verdict on it before the next one."""
    tally = _Tally()
    for i, case in enumerate(cases):
        before, seen = node.snapshot, len(peer.statuses)
        is_request = case.topic in ("goal_pose", "goal_joints")

        def answered(
            before: Any = before, seen: int = seen, case: mf.Case = case, is_request: bool = is_request
        ) -> bool:
            if node.snapshot is not before or peer.error_reports(seen):
                return True
            return is_request and bool(peer.summaries(seen, request=case.topic))

        peer.publishers[case.topic].publish(case.message)
        if not _spin_until(executor, answered, ANSWER_TIMEOUT):
            tally.problem(f"case {i} {case.kind}: no answer within {ANSWER_TIMEOUT} s")
            continue
        errors = peer.error_reports(seen)
        if errors:
            tally.refused[case.kind] += 1
            text = str(errors[0].message)
            if node.snapshot is not before:
                tally.problem(f"case {i} {case.kind}: refused ({text}) but the map changed")
            if case.topic not in text:
                tally.problem(f"case {i} {case.kind}: error does not name topic {case.topic!r}: {text}")
            if case.reasons and not any(r in text.lower() for r in case.reasons):
                tally.problem(f"case {i} {case.kind}: error gives none of the reasons {case.reasons}: {text}")
            if "\n" in text or any(mark in text for mark in TRACEBACK_MARKS):
                tally.problem(f"case {i} {case.kind}: error is not one clear line: {text!r}")
            if text not in node.errors:
                tally.problem(f"case {i} {case.kind}: /diagnostics error missing from node.errors: {text}")
        else:
            tally.accepted[case.kind] += 1
            if case.must_fail:
                got = [(str(s.name), str(s.message), _values(s)) for _, s in peer.statuses[seen:]]
                tally.problem(f"case {i} {case.kind}: a malformed message was accepted; got {got}")
            _settle(executor, peer, node=node)
            tally.followups += len(peer.error_reports(seen))
    return tally


def _settle(
    executor: Any, peer: _Peer, quiet: float = 0.03, step: float = 0.005, node: PlannerNode | None = None
) -> None:
    """Spin until the executor was idle for ``quiet`` seconds (a replan or plan after an accepted message).

    ``spin_once`` returns early when it ran a callback and late when the callback was long; only
    spins that waited out their ``step`` (nothing to do) while ``node``'s planning thread had nothing
    to do either count towards the quiet time (a replan runs in that thread, not in a callback).
    """
    last, count = time.monotonic(), len(peer.statuses) + len(peer.plans)
    while time.monotonic() - last < quiet:
        t0 = time.monotonic()
        executor.spin_once(timeout_sec=step)
        took = time.monotonic() - t0
        now = len(peer.statuses) + len(peer.plans)
        busy = node is not None and not node.planning_idle
        if busy or now != count or not 0.8 * step <= took <= 3 * step:
            last, count = time.monotonic(), now


def _decode_path(points: np.ndarray, free: set[int], session: QuerySession) -> list[int] | None:
    """Edges, all in ``free``, whose samples chained from the start give exactly ``points`` (K, d).

    ``d`` leading state coordinates are compared: x, y, z of the helicopter, the arm's joint angles.
    """
    edges = session.domain.graph.edges
    start, goal = int(session.domain.start), int(session.domain.goal)
    d = points.shape[1]

    def walk(pos: int, vertex: int, used: list[int]) -> list[int] | None:
        if pos == len(points) - 1 and vertex == goal:
            return used
        for e in free:
            u, v = int(edges[e, 0]), int(edges[e, 1])
            if vertex not in (u, v) or e in used:
                continue
            states = session.edge_states(e)[:, :d]
            states = states if u == vertex else states[::-1]
            end = pos + len(states)
            if end <= len(points) and np.allclose(points[pos:end], states, atol=1e-6):
                found = walk(end - 1, v if u == vertex else u, [*used, e])
                if found is not None:
                    return found
        return None

    return walk(0, start, [])


def _free_edges(checks: Any) -> set[int]:
    return {int(s.name.split("/")[1]) for s in checks.status if s.level == b"\x00"}


def _verify_plans(peer: _Peer, session: QuerySession) -> int:
    """Every plan received decodes into edges checked free in the edge_checks of its stamp.

    Helicopter: the Path's positions; arm: the JointTrajectory's configurations. An empty plan is a
    withdrawal (the node's way of taking a plan back) and is not a plan. Returns the plans verified.
    """
    if session.domain.publishes_joint_trajectory:
        plans = [(_stamp(t), np.array([list(p.positions) for p in t.points])) for t in peer.trajectories]
    else:
        plans = [
            (
                _stamp(p),
                np.array([[q.pose.position.x, q.pose.position.y, q.pose.position.z] for q in p.poses]),
            )
            for p in peer.plans
        ]
    verified = 0
    for stamp, points in plans:
        if len(points) == 0:
            continue
        checks = peer.checks.get(stamp)
        assert checks is not None, f"plan stamped {stamp} has no edge_checks with that stamp"
        assert _decode_path(points, _free_edges(checks), session) is not None, (
            f"plan stamped {stamp} is not made of edges checked free in its edge_checks"
        )
        verified += 1
    return verified


def _offline_plan(session_tree: Path, markers: Any, cloud: Any | None, frame: str, margin: float) -> Any:
    terrain = terrain_from_cloud(cloud, frame_id=frame) if cloud is not None else None
    snapshot = MapSnapshot(1, obstacle_map(markers, frame_id=frame), terrain, margin)
    offline_session = QuerySession(load_prior(session_tree), name="offline")
    return offline_session.plan(snapshot, *own_query(offline_session), seed=0)


def _start(ctx: Any, tree: Path, frame: str) -> tuple[PlannerNode, _Peer, Any]:
    node = PlannerNode(
        context=ctx,
        parameter_overrides=[
            Parameter("prior_paths", value=[str(tree)]),
            Parameter("frame_id", value=frame),
            Parameter("start_without_robot_state", value="prior_start"),
        ],
    )
    peer = _Peer.create(ctx)
    executor = SingleThreadedExecutor(context=ctx)
    executor.add_node(node)
    executor.add_node(peer.node)
    assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS
    assert node.trigger_activate() == TransitionCallbackReturn.SUCCESS
    return node, peer, executor


def _report(tally: _Tally, seconds: float, cases: int) -> None:
    print(f"\n{cases} messages in {seconds:.1f} s ({1e3 * seconds / max(cases, 1):.1f} ms each)")
    print(f"refused {sum(tally.refused.values())}: {dict(sorted(tally.refused.items()))}")
    print(f"accepted {sum(tally.accepted.values())}: {dict(sorted(tally.accepted.items()))}")
    print(f"error reports after accepted messages (plan withdrawn on a map update): {tally.followups}")


def _final_problems(tally: _Tally, peer: _Peer, executor: Any) -> None:
    _settle(executor, peer, quiet=0.1)
    refused, reports = sum(tally.refused.values()), len(peer.error_reports())
    if reports != refused + tally.followups:
        tally.problem(
            f"{reports} error reports for {refused} refused messages and {tally.followups} withdrawals"
            " (want exactly one per refused message)"
        )
    assert not tally.problems, "\n".join(tally.problems)


def test_generator_is_seeded_and_its_malformed_cases_are_refused_offline() -> None:
    """The cases are a function of the seed, and the map store refuses each must-fail one with its reason."""
    session = QuerySession(load_prior(HELI_TREE), name="heli")
    markers, cloud = mf.helicopter_bases(session.domain, seed=3)
    a = mf.marker_cases(np.random.default_rng(5), markers, count=200)
    b = mf.marker_cases(np.random.default_rng(5), markers, count=200)
    assert [c.kind for c in a] == [c.kind for c in b]
    assert [repr(c.message) for c in a] == [repr(c.message) for c in b]  # repr: NaN-safe, no CDR padding
    clouds = mf.cloud_cases(np.random.default_rng(6), cloud, count=200)
    assert len({c.kind for c in a}) >= 12
    assert len({c.kind for c in clouds}) >= 12
    for case in [*a, *clouds]:
        error = _offline_error(case)
        if error is None:
            assert not case.must_fail, f"{case.kind} was accepted offline"
        else:
            assert case.reasons == () or any(r in error.lower() for r in case.reasons), (case.kind, error)


def _offline_error(case: mf.Case) -> str | None:
    """The refusal the node's map store gives a map case, or None if it accepts it."""
    try:
        MapStore(frame_id="map").apply(case.topic, case.message)
    except (MessageError, DrdError) as exc:
        return str(exc)
    return None


def test_helicopter_node_survives_thousands_of_malformed_messages(
    context: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(node_module, "STATE_ERROR_PERIOD_S", 0.0)  # one report per odometry case, unthrottled
    node, peer, executor = _start(context, HELI_TREE, "map")
    try:
        session = node.sessions[0]
        markers, cloud = mf.helicopter_bases(session.domain, seed=3)
        goal = mf.valid_goal(session.goal_state, frame_id="map")
        rng = np.random.default_rng(2024)
        cases = mf.interleave(
            rng,
            mf.marker_cases(rng, markers, count=1300),
            mf.cloud_cases(rng, cloud, count=600),
            mf.goal_cases(rng, goal, count=500, tolerance=float(node.get_parameter("goal_tolerance").value)),
            mf.odom_cases(
                rng, mf.valid_odometry(session.vertex_state(session.domain.start), frame_id="map"), count=200
            ),
        )
        # Valid maps first, so that "unchanged" means something and valid-after-mutation goals plan.
        peer.publishers["terrain"].publish(cloud)
        peer.publishers["obstacles"].publish(markers)
        assert _spin_until(executor, lambda: node.snapshot.version >= 2, 10.0)
        t0 = time.monotonic()
        tally = _feed(executor, node, peer, cases)
        _report(tally, time.monotonic() - t0, len(cases))
        assert sum(tally.refused.values()) >= 0.9 * len(cases)
        # The valid maps again, then a valid request: the same plan as offline, verified edge by edge.
        version = node.snapshot.version
        peer.publishers["terrain"].publish(cloud)
        peer.publishers["obstacles"].publish(markers)
        assert _spin_until(executor, lambda: node.snapshot.version >= version + 2, 10.0)
        _settle(executor, peer)
        plans = len(peer.plans)
        peer.publishers["goal_pose"].publish(goal)
        assert _spin_until(executor, lambda: len(peer.plans) > plans, 10.0), "no plan for the valid request"
        _final_problems(tally, peer, executor)
        offline = _offline_plan(HELI_TREE, markers, cloud, "map", session.margin)
        assert offline.ok
        last = peer.plans[-1]
        np.testing.assert_allclose(
            [[p.pose.position.x, p.pose.position.y, p.pose.position.z] for p in last.poses],
            offline.states[:, :3],
        )
        assert _verify_plans(peer, session) >= 1
    finally:
        executor.shutdown()
        node.destroy_node()
        peer.node.destroy_node()


#: Seconds DDS discovery may take to match the peer's publishers with the node's arm subscriptions (a
#: loaded machine takes seconds; a node without these subscriptions never matches).
DISCOVERY_S = 20.0


def _arm_interfaces_ready(peer: _Peer, executor: Any) -> bool:
    def ready() -> bool:
        pubs = peer.publishers
        return all(pubs[t].get_subscription_count() > 0 for t in ("goal_joints", "robot_description"))

    return _spin_until(executor, ready, DISCOVERY_S)


def test_arm_node_survives_malformed_joints_descriptions_and_markers(context: Any) -> None:
    node, peer, executor = _start(context, ARM_TREE, "panda_link0")
    try:
        assert _arm_interfaces_ready(peer, executor), (
            f"no goal_joints / robot_description subscription of the node matched within {DISCOVERY_S:g} s"
        )
        session = node.sessions[0]
        domain: Any = session.domain
        markers = mf.arm_bases(domain, seed=4)  # a world with a free library path
        names = [f"panda_joint{i}" for i in range(1, 8)]
        joints = mf.valid_joints(names, session.goal_state)
        tip = session.goal_position
        tolerance = float(node.get_parameter("goal_tolerance").value)
        rng = np.random.default_rng(77)
        cases = mf.interleave(
            rng,
            mf.marker_cases(rng, markers, count=300),
            mf.joint_cases(rng, joints, count=200),
            mf.description_cases(rng, PANDA_URDF.read_text(), count=100),
            mf.goal_cases(rng, mf.valid_goal(tip, frame_id="panda_link0"), count=60, tolerance=tolerance),
        )
        peer.publishers["obstacles"].publish(markers)
        assert _spin_until(executor, lambda: node.snapshot.version >= 1, 10.0)
        t0 = time.monotonic()
        tally = _feed(executor, node, peer, cases)
        _report(tally, time.monotonic() - t0, len(cases))
        version = node.snapshot.version
        peer.publishers["obstacles"].publish(markers)
        assert _spin_until(executor, lambda: node.snapshot.version > version, 10.0)
        _settle(executor, peer)
        count = len(peer.trajectories)
        peer.publishers["goal_joints"].publish(joints)
        assert _spin_until(executor, lambda: len(peer.trajectories) > count, 20.0), "no plan for valid joints"
        _final_problems(tally, peer, executor)
        offline = _offline_plan(ARM_TREE, markers, None, "panda_link0", session.margin)
        assert offline.ok
        np.testing.assert_allclose([list(p.positions) for p in peer.trajectories[-1].points], offline.states)
        assert _verify_plans(peer, session) >= 1
    finally:
        executor.shutdown()
        node.destroy_node()
        peer.node.destroy_node()
