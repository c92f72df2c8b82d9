"""Replan only when needed: which plan edges a map update can reach, and re-checking just those.

Helicopter (trees/heli_wires.npz) and arm (trees/arm_table_clutter.npz) with real FCL scenes. The
brute-force tests check the safety argument: every edge whose full check turns from free to blocked after
a random obstacle is added is among the edges :func:`affected_edges` reports.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import own_query
from rosbags.typesys import Stores, get_typestore

from drd_msgs_py.factory import RosbagsMessages
from drd_planner.domains.arm import ArmDomain, default_panda_dir
from drd_planner.domains.helicopter import HelicopterDomain
from drd_planner.domains.helicopter_worlds import world_parts
from drd_planner.exceptions import PlanningError, ProblemError
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Box, Capsule, Cylinder, Shape, Sphere
from drd_planner.geometry.terrain import Heightfield
from drd_planner.planner import load_prior
from drd_planner.planning.map_intake import obstacle_map, terrain_from_cloud
from drd_planner.planning.map_state import MapSnapshot, Parts, changed_parts
from drd_planner.planning.replan import (
    affected_edges,
    cached_sweep_edges,
    differing_parts,
    edge_sweep_boxes,
    recheck_plan,
)
from drd_planner.planning.session import QuerySession
from drd_planner.planning.session_plan import SessionPlan
from drd_planner.planning.world_messages import helicopter_world_messages

TREES = Path(__file__).resolve().parents[2] / "trees"
HELI_SEED = 2  # a Wires world whose plan has 6 edges
ARM_SEED = 4  # a Table+Clutter world whose plan has 4 edges


def _with(snapshot: MapSnapshot, extra: dict[str, Parts]) -> MapSnapshot:
    return snapshot.with_obstacles({**snapshot.obstacles, **extra})


def _random_pose(rng: np.random.Generator, centre: np.ndarray) -> Pose:
    quaternion = rng.normal(size=4)
    return Pose(centre, quaternion / np.linalg.norm(quaternion))


def _random_shape(rng: np.random.Generator, scale: float) -> Shape:
    kind = int(rng.integers(4))
    a, b = (float(x) for x in rng.uniform(0.05, 1.0, size=2) * scale)
    if kind == 0:
        return Box(rng.uniform(0.05, 1.0, size=3) * scale)
    if kind == 1:
        return Sphere(a / 2)
    if kind == 2:
        return Cylinder(a / 2, b)
    return Capsule(a / 4, b)


# --------------------------------------------------------------------------------------------------
# Helicopter


@pytest.fixture(scope="module")
def heli() -> tuple[QuerySession, MapSnapshot, SessionPlan]:
    session = QuerySession(load_prior(TREES / "heli_wires.npz"), name="heli_wires")
    domain = session.domain
    assert isinstance(domain, HelicopterDomain)
    world = domain.make_world("wires", HELI_SEED)
    parts = {name: ((shape, pose),) for name, shape, pose in world_parts(world, wire_segments=8)}
    snapshot = MapSnapshot(1, parts, world.terrain, session.margin)
    plan = session.plan(snapshot, *own_query(session), seed=0)
    assert plan.ok
    assert len(plan.path_edges) >= 3
    return session, snapshot, plan


def test_heli_sweep_boxes_hold_every_checked_sphere(
    heli: tuple[QuerySession, MapSnapshot, SessionPlan],
) -> None:
    session, _, plan = heli
    domain = session.domain
    assert isinstance(domain, HelicopterDomain)
    reach = domain.vehicle_radius + session.margin
    lo, hi = edge_sweep_boxes(session, plan.path_edges)
    assert lo.shape == hi.shape == (len(plan.path_edges), 3)
    for k, e in enumerate(plan.path_edges):
        xyz = domain.lattice.trajectory(e)[:, :3]  # what the checker sweeps
        assert np.all(xyz - reach >= lo[k])
        assert np.all(xyz + reach <= hi[k])
        # Not absurdly loose: at most half a sample spacing (plus slack) beyond the swept spheres.
        slack = 0.5 * domain.lattice.params.sample_spacing + 1e-3
        assert np.all(lo[k] >= xyz.min(axis=0) - reach - slack)
    bigger_lo, bigger_hi = edge_sweep_boxes(session, plan.path_edges, margin=session.margin + 3.0)
    np.testing.assert_allclose(bigger_hi - hi, 3.0)
    np.testing.assert_allclose(lo - bigger_lo, 3.0)


def test_sweep_boxes_are_cached_only_for_the_edges_asked() -> None:
    session = QuerySession(load_prior(TREES / "heli_wires.npz"), name="fresh")
    assert cached_sweep_edges(session) == frozenset()
    edge_sweep_boxes(session, [5, 7, 5])
    assert cached_sweep_edges(session) == {5, 7}
    first = edge_sweep_boxes(session, [7])
    edge_sweep_boxes(session, [9])
    assert cached_sweep_edges(session) == {5, 7, 9}
    np.testing.assert_array_equal(edge_sweep_boxes(session, [7])[0], first[0])
    empty_lo, _ = edge_sweep_boxes(session, [])
    assert empty_lo.shape == (0, 3)
    with pytest.raises(PlanningError, match="not in"):
        edge_sweep_boxes(session, [session.domain.graph.num_edges])
    with pytest.raises(PlanningError, match="margin"):
        edge_sweep_boxes(session, [1], margin=-1.0)


def test_heli_far_obstacle_affects_nothing(heli: tuple[QuerySession, MapSnapshot, SessionPlan]) -> None:
    session, snapshot, plan = heli
    far = _with(snapshot, {"probe/far": ((Box([20.0, 20.0, 20.0]), Pose([5000.0, 4000.0, 100.0])),)})
    assert affected_edges(session, plan.path_edges, snapshot, far) == ()
    result = recheck_plan(session, plan.path_edges, snapshot, far)
    assert result.kept
    assert result.rechecked == ()
    assert result.blocked == ()
    assert result.check_ms == ()
    assert result.map_version == far.version
    assert "plan kept" in result.reason
    # Nothing changed at all: no check either.
    same = recheck_plan(session, plan.path_edges, snapshot, snapshot.with_obstacles(snapshot.obstacles))
    assert same.kept
    assert same.affected == ()
    assert not same.all_edges


def test_heli_box_on_a_plan_edge_blocks_it(heli: tuple[QuerySession, MapSnapshot, SessionPlan]) -> None:
    session, snapshot, plan = heli
    edge = plan.path_edges[len(plan.path_edges) // 2]
    states = session.edge_states(edge)
    middle = states[states.shape[0] // 2, :3]
    new = _with(snapshot, {"probe/mid": ((Box([3.0, 3.0, 3.0]), Pose(middle)),)})
    affected = affected_edges(session, plan.path_edges, snapshot, new)
    assert edge in affected
    assert len(affected) < len(plan.path_edges)
    result = recheck_plan(session, plan.path_edges, snapshot, new)
    assert not result.kept
    assert result.blocked == (edge,)
    assert result.rechecked[-1] == edge
    assert set(result.rechecked) <= set(affected)
    assert len(result.check_ms) == len(result.rechecked)
    assert result.total_check_ms > 0.0
    assert f"plan edge {edge} blocked" in result.reason
    assert "replanning" in result.reason
    assert session.checker(new).check(edge) is False  # the full check agrees


def test_heli_small_change_near_the_plan_is_rechecked_and_kept(
    heli: tuple[QuerySession, MapSnapshot, SessionPlan],
) -> None:
    session, snapshot, plan = heli
    domain = session.domain
    assert isinstance(domain, HelicopterDomain)
    edge = plan.path_edges[len(plan.path_edges) // 2]
    states = session.edge_states(edge)
    above = states[states.shape[0] // 2, :3] + [0.0, 0.0, domain.vehicle_radius + session.margin + 1.5]
    new = _with(snapshot, {"probe/above": ((Sphere(0.5), Pose(above)),)})
    result = recheck_plan(session, plan.path_edges, snapshot, new)
    assert edge in result.affected
    assert len(result.rechecked) > 0
    assert result.kept
    assert result.blocked == ()
    assert result.rechecked == result.affected
    assert "re-checked free; plan kept" in result.reason
    assert bool(session.checker(new).check_many(plan.path_edges).all())


def test_heli_terrain_change_rechecks_every_edge(
    heli: tuple[QuerySession, MapSnapshot, SessionPlan],
) -> None:
    session, snapshot, plan = heli
    terrain = snapshot.terrain
    assert terrain is not None
    lower = snapshot.with_terrain(Heightfield(terrain.origin, terrain.cell_size, terrain.heights - 1.0))
    assert affected_edges(session, plan.path_edges, snapshot, lower) == plan.path_edges
    result = recheck_plan(session, plan.path_edges, snapshot, lower)
    assert result.kept
    assert result.all_edges
    assert result.rechecked == plan.path_edges
    assert "terrain" in result.reason
    flooded = snapshot.with_terrain(Heightfield(terrain.origin, terrain.cell_size, terrain.heights + 2000.0))
    drowned = recheck_plan(session, plan.path_edges, snapshot, flooded)
    assert not drowned.kept
    assert drowned.blocked == (plan.path_edges[0],)
    assert drowned.all_edges
    # The same heights in a new object are no change; another margin changes every check.
    copy = snapshot.with_terrain(Heightfield(terrain.origin, terrain.cell_size, terrain.heights.copy()))
    assert affected_edges(session, plan.path_edges, snapshot, copy) == ()
    wider = MapSnapshot(2, snapshot.obstacles, terrain, snapshot.margin + 1.0)
    assert affected_edges(session, plan.path_edges, snapshot, wider) == plan.path_edges


def test_heli_map_resent_through_messages_is_compared_by_value(
    heli: tuple[QuerySession, MapSnapshot, SessionPlan],
) -> None:
    session, _, _ = heli
    domain = session.domain
    assert isinstance(domain, HelicopterDomain)
    msgs = RosbagsMessages(get_typestore(Stores.ROS2_JAZZY))
    world = domain.make_world("wires", HELI_SEED)

    def snapshot_of(version: int) -> MapSnapshot:
        markers, cloud = helicopter_world_messages(world, wire_segments=8, frame_id="map", msgs=msgs)
        obstacles = obstacle_map(markers, frame_id="map")
        terrain = terrain_from_cloud(cloud, frame_id="map")
        return MapSnapshot(version, obstacles, terrain, session.margin)

    first = snapshot_of(1)
    plan = session.plan(first, *own_query(session), seed=0)
    assert plan.ok
    again = snapshot_of(2)  # DELETEALL + every marker again: new objects, same geometry
    assert differing_parts(first, again) == []
    result = recheck_plan(session, plan.path_edges, first, again)
    assert result.kept
    assert result.rechecked == ()
    renamed = again.with_obstacles({f"renamed/{k}": parts for k, parts in again.obstacles.items()})
    assert changed_parts(first, renamed)  # per key, every part moved ...
    assert differing_parts(first, renamed) == []  # ... but the scene is the same
    assert affected_edges(session, plan.path_edges, first, renamed) == ()
    edge = plan.path_edges[0]
    start = session.edge_states(edge)[0, :3]
    moved = _with(again, {"probe/0": ((Sphere(1.0), Pose(start)),)})
    assert len(differing_parts(first, moved) or []) == 1
    assert edge in affected_edges(session, plan.path_edges, first, moved)


def test_heli_affected_edges_are_conservative(heli: tuple[QuerySession, MapSnapshot, SessionPlan]) -> None:
    session, snapshot, plan = heli
    rng = np.random.default_rng(20240605)
    graph = session.domain.graph
    path_xyz = plan.states[:, :3]
    # Edges under test: the plan's and others that start near the plan (free on the old map).
    starts = np.array([session.edge_states(e)[0, :3] for e in range(graph.num_edges)])
    dist = np.min(np.linalg.norm(starts[:, None, :] - path_xyz[None, ::4], axis=2), axis=1)
    nearby = np.flatnonzero(dist < 40.0)
    pool = np.unique(np.concatenate([plan.path_edges, rng.choice(nearby, size=min(120, nearby.size), replace=False)]))
    pool = pool[session.checker(snapshot).check_many(pool)]
    assert pool.size > 50
    events = near_but_free = pruned = 0
    for k in range(40):
        centre = path_xyz[rng.integers(path_xyz.shape[0])] + rng.normal(0.0, 10.0, size=3)
        new = _with(snapshot, {f"probe/{k}": ((_random_shape(rng, 15.0), _random_pose(rng, centre)),)})
        affected = set(affected_edges(session, pool.tolist(), snapshot, new))
        coarse = set(affected_edges(session, pool.tolist(), snapshot, new, refine=False))
        assert affected <= coarse
        free = session.checker(new).check_many(pool)
        newly_blocked = set(pool[~free].tolist())
        assert newly_blocked <= affected, f"case {k}: blocked edges {newly_blocked - affected} not reported"
        events += len(newly_blocked)
        near_but_free += len(affected - newly_blocked)
        pruned += pool.size - len(affected)
    # the test saw all three kinds of edge
    assert events >= 10
    assert near_but_free > 0
    assert pruned > 0


# --------------------------------------------------------------------------------------------------
# Arm


@pytest.fixture(scope="module")
def arm() -> tuple[QuerySession, MapSnapshot, SessionPlan]:
    try:
        default_panda_dir()
    except ProblemError as exc:
        pytest.skip(str(exc))
    session = QuerySession(load_prior(TREES / "arm_table_clutter.npz"), name="arm_table_clutter")
    domain = session.domain
    assert isinstance(domain, ArmDomain)
    world = domain.make_world("table_clutter", ARM_SEED)
    parts = {o.name: ((o.shape, o.pose),) for o in world.obstacles}
    snapshot = MapSnapshot(1, parts, None, session.margin)
    plan = session.plan(snapshot, *own_query(session), seed=0)
    assert plan.ok
    assert len(plan.path_edges) >= 3
    return session, snapshot, plan


def test_arm_sweep_boxes_hold_the_continuous_motion(
    arm: tuple[QuerySession, MapSnapshot, SessionPlan],
) -> None:
    session, _, plan = arm
    domain = session.domain
    assert isinstance(domain, ArmDomain)
    states = domain.graph.vertex_states
    assert states is not None
    radii = domain.robot.spheres.radii
    lo, hi = edge_sweep_boxes(session, plan.path_edges, margin=0.01)
    for k, e in enumerate(plan.path_edges):
        u, v = domain.graph.edges[e]
        t = np.linspace(0.0, 1.0, 400)  # far finer than the checker's samples
        centres = domain.robot.sphere_centres(states[u] + t[:, None] * (states[v] - states[u]))
        assert np.all(centres - radii[:, None] - 0.01 >= lo[k])
        assert np.all(centres + radii[:, None] + 0.01 <= hi[k])


def test_arm_far_obstacle_and_blocking_box(arm: tuple[QuerySession, MapSnapshot, SessionPlan]) -> None:
    session, snapshot, plan = arm
    domain = session.domain
    assert isinstance(domain, ArmDomain)
    far = _with(snapshot, {"probe/far": ((Box([0.1, 0.1, 0.1]), Pose([3.0, 3.0, 0.5])),)})
    result = recheck_plan(session, plan.path_edges, snapshot, far)
    assert result.kept
    assert result.affected == ()
    assert result.rechecked == ()
    states = domain.graph.vertex_states
    assert states is not None
    edge = plan.path_edges[len(plan.path_edges) // 2]
    u, v = domain.graph.edges[edge]
    q_mid = (states[u] + states[v]) / 2.0
    hand = domain.robot.fk.link_pose(q_mid, domain.robot.chain.tip_link)[0, :3, 3]
    new = _with(snapshot, {"probe/hand": ((Box([0.05, 0.05, 0.05]), Pose(hand)),)})
    assert session.checker(new).check(edge) is False
    result = recheck_plan(session, plan.path_edges, snapshot, new)
    assert edge in result.affected
    assert not result.kept
    assert len(result.blocked) == 1
    assert session.checker(new).check(result.blocked[0]) is False
    assert "replanning" in result.reason


def test_arm_affected_edges_are_conservative(arm: tuple[QuerySession, MapSnapshot, SessionPlan]) -> None:
    session, snapshot, plan = arm
    domain = session.domain
    assert isinstance(domain, ArmDomain)
    rng = np.random.default_rng(77)
    pool = np.unique(np.concatenate([plan.path_edges, rng.choice(domain.graph.num_edges, 60, replace=False)]))
    pool = pool[session.checker(snapshot).check_many(pool)]
    centres = domain.robot.sphere_centres(plan.states).reshape(-1, 3)
    events = near_but_free = pruned = 0
    for k in range(20):
        centre = centres[rng.integers(centres.shape[0])] + rng.normal(0.0, 0.15, size=3)
        new = _with(snapshot, {f"probe/{k}": ((_random_shape(rng, 0.12), _random_pose(rng, centre)),)})
        affected = set(affected_edges(session, pool.tolist(), snapshot, new))
        free = session.checker(new).check_many(pool)
        newly_blocked = set(pool[~free].tolist())
        assert newly_blocked <= affected, f"case {k}: blocked edges {newly_blocked - affected} not reported"
        events += len(newly_blocked)
        near_but_free += len(affected - newly_blocked)
        pruned += pool.size - len(affected)
        plan_only = recheck_plan(session, plan.path_edges, snapshot, new)
        assert plan_only.kept == bool(session.checker(new).check_many(plan.path_edges).all())
    assert events >= 3
    assert near_but_free > 0
    assert pruned > 0
