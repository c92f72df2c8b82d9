"""QuerySession, the online session: any query of a world prior (or a tree file's own query) on real FCL maps.

From where the robot is, cached per map snapshot, re-checked after updates.

The priors are built in the test from small generated datasets (a 300 m x 200 m helicopter lattice in Wires
worlds, a 150-sample Panda roadmap in Table+Clutter worlds), so nothing outside the repository is needed
but the shared Panda model (the arm tests skip without it).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import SHARED_DATA, own_query

from drd_planner.cli.main import main
from drd_planner.core.episode import run_episode
from drd_planner.core.policies import POLICIES, PolicyContext
from drd_planner.core.status import PlanCause, PlanStatus
from drd_planner.data.tree_file import save_tree
from drd_planner.domains.arm import ArmDomain
from drd_planner.domains.helicopter import HelicopterDomain
from drd_planner.domains.helicopter_worlds import world_parts
from drd_planner.domains.pose_states import state_from_pose, yaw_from_quaternion
from drd_planner.exceptions import PlanningError, PriorFileError, ProblemError, TreeFileError
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Box
from drd_planner.geometry.terrain import Heightfield
from drd_planner.planner import WorldPrior, load_prior, load_tree_bundle
from drd_planner.planner.anytime import ImproveBudget
from drd_planner.planning.map_state import MapSnapshot, Parts
from drd_planner.planning.replan import affected_edges, recheck_plan
from drd_planner.planning.session import QuerySession
from drd_planner.planning.session_motions import MotionRegistry
from drd_planner.planning.session_plan import SessionPlan

TREES = Path(__file__).resolve().parents[2] / "trees"
HELI_SPEC = '{"lattice": {"x_range": [0.0, 300.0], "y_range": [-100.0, 100.0], "goal": [300.0, 0.0]}}'
ARM_SPEC = '{"num_samples": 150, "k": 6, "seed": 3}'
HELI_GOAL = 16  # (250, 0, 65): not the tree's goal (300, 0, 65)
ARM_GOALS = (5, 30, 77)  # not the tree's goal (vertex 1)


def _build_prior(folder: Path, domain: str, model: str, spec: str) -> WorldPrior:
    dataset, prior = folder / "data.npz", folder / "prior.npz"
    argv = ["build-dataset", "--domain", domain, "--world-model", model, "--worlds", "40", "--seed", "3"]
    argv += ["--out", str(dataset), "--workers", "1", "--domain-spec", spec]
    assert main(argv) == 0
    argv = ["build-tree", "--dataset", str(dataset), "--out", str(prior), "--eta", "0.2", "--kappa", "10"]
    assert main(argv) == 0
    return load_prior(prior, expected_domain=domain)


@pytest.fixture(scope="module")
def heli_prior(tmp_path_factory: pytest.TempPathFactory) -> WorldPrior:
    return _build_prior(tmp_path_factory.mktemp("heli"), "helicopter", "wires", HELI_SPEC)


def _heli_parts(session: QuerySession, seed: int) -> tuple[dict[str, Parts], Heightfield | None]:
    domain = session.domain
    assert isinstance(domain, HelicopterDomain)
    world = domain.make_world("wires", seed)
    return {name: ((shape, pose),) for name, shape, pose in world_parts(world, wire_segments=8)}, world.terrain


def _heli_snapshot(session: QuerySession, seed: int) -> MapSnapshot:
    parts, terrain = _heli_parts(session, seed)
    return MapSnapshot(1, parts, terrain, session.margin)


def _heli_start(session: QuerySession) -> np.ndarray:
    """30 m behind vertex 0 (the tree's start), same altitude and heading."""
    return session.vertex_state(0) + np.array([-30.0, 0.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def heli_plan(heli_prior: WorldPrior) -> tuple[QuerySession, MapSnapshot, SessionPlan]:
    """The first Wires world (from seed 100) with a free path from the off-graph start to HELI_GOAL."""
    session = QuerySession(heli_prior, name="heli")
    for seed in range(100, 130):
        snapshot = _heli_snapshot(session, seed)
        result = session.plan(snapshot, _heli_start(session), HELI_GOAL, seed=0)
        if result.ok:
            return session, snapshot, result
    raise AssertionError("no world with a free path")


def _independent_checker(session: QuerySession, snapshot: MapSnapshot) -> Any:
    """A checker on a new scene of the same maps (no cached outcome, no shared scene)."""
    fresh = MapSnapshot(snapshot.version, dict(snapshot.obstacles), snapshot.terrain, snapshot.margin)
    return session.domain.checker(fresh.scene)


# --------------------------------------------------------------------------------------------------
# Helicopter


def test_off_graph_start_to_another_goal_on_a_real_map(
    heli_plan: tuple[QuerySession, MapSnapshot, SessionPlan],
) -> None:
    session, snapshot, result = heli_plan
    prior, start = session.prior, _heli_start(session)
    num_edges = prior.graph.num_edges
    assert HELI_GOAL != prior.trees[0].goal
    assert np.linalg.norm(start - session.vertex_state(0)) == pytest.approx(30.0)
    assert result.ok
    assert result.status is PlanStatus.FOUND
    assert result.query == "connected"
    assert result.stage in ("tree", "bisect", "graph")
    assert result.stage in result.message
    # The path starts at the robot's state and ends at the goal vertex.
    np.testing.assert_allclose(result.states[0], start)
    np.testing.assert_allclose(result.states[-1], session.vertex_state(HELI_GOAL))
    assert result.path_vertices[0] == prior.graph.num_vertices
    assert result.path_vertices[-1] == HELI_GOAL
    motions = [e for e in result.path_edges if e >= num_edges]
    assert motions == [result.path_edges[0]]  # the start is joined by one new motion
    np.testing.assert_allclose(session.edge_states(motions[0])[0], start)
    # Every path edge, the motion included, was checked free in this plan.
    checked = {c.edge: c.free for c in result.checks}
    assert all(checked.get(e) is True for e in result.path_edges)
    assert {c.stage for c in result.checks} <= {"tree", "bisect", "graph"}
    # Dense states: at most one sample spacing (5 m, horizontal) apart, and free by an independent FCL check.
    steps = np.linalg.norm(np.diff(result.states[:, :2], axis=0), axis=1)
    assert steps.max() <= 5.0 + 1e-6
    assert result.states.shape[0] > 2 * len(result.path_edges)
    checker = _independent_checker(session, snapshot)
    assert checker.check_motion(result.states)
    for e in result.path_edges:
        assert checker.check_motion(session.edge_states(e))
    assert set(result.seconds) >= {"prepare", "checks", "selection", "library", "policy", "total"}


def test_every_found_path_is_free_and_every_failure_has_a_status(heli_prior: WorldPrior) -> None:
    session = QuerySession(heli_prior, name="heli")
    start = _heli_start(session)
    statuses = set()
    for seed in range(100, 108):
        snapshot = _heli_snapshot(session, seed)
        checker = _independent_checker(session, snapshot)
        for goal in (HELI_GOAL, 9, 13):
            result = session.plan(snapshot, start, goal, seed=seed)
            statuses.add(result.status)
            truth = {c.edge: bool(checker.check_motion(session.edge_states(c.edge))) for c in result.checks}
            assert truth == {c.edge: c.free for c in result.checks}  # every outcome is the FCL answer
            if result.ok:
                assert checker.check_motion(result.states)
                np.testing.assert_allclose(result.states[0], start)
                np.testing.assert_allclose(result.states[-1], session.vertex_state(goal))
            else:
                assert result.status is PlanStatus.NO_PATH
                assert result.path_edges == ()
                assert "blocked" in result.message
    assert statuses == {PlanStatus.FOUND, PlanStatus.NO_PATH}


def test_same_seed_same_checks_and_the_snapshot_cache(
    heli_plan: tuple[QuerySession, MapSnapshot, SessionPlan],
) -> None:
    session, snapshot, first = heli_plan
    fresh = QuerySession(session.prior, name="again")
    start = _heli_start(session)
    other = fresh.plan(snapshot, start, HELI_GOAL, seed=0)
    assert [(c.edge, c.free, c.stage) for c in other.checks] == [(c.edge, c.free, c.stage) for c in first.checks]
    assert other.path_edges == first.path_edges
    np.testing.assert_array_equal(other.states, first.states)
    # The same session on the same snapshot: the same motion ids, every answer from the cache.
    again = fresh.plan(snapshot, start, HELI_GOAL, seed=0)
    assert [c.edge for c in again.checks] == [c.edge for c in first.checks]
    assert all(c.cached and c.check_ms == 0.0 for c in again.checks)
    assert not any(c.cached for c in other.checks)
    # A new snapshot of the same maps is a new map version: its checks are made again.
    moved = snapshot.with_obstacles(snapshot.obstacles)
    third = fresh.plan(moved, start, HELI_GOAL, seed=0)
    assert [c.edge for c in third.checks] == [c.edge for c in first.checks]
    assert not any(c.cached for c in third.checks)
    assert third.map_version == snapshot.version + 1


def test_a_goal_state_and_a_vertex_id_are_the_same_goal(
    heli_plan: tuple[QuerySession, MapSnapshot, SessionPlan],
) -> None:
    session, snapshot, first = heli_plan
    goal = session.goal_state_from_position(session.vertex_state(HELI_GOAL)[:3], yaw=0.0)
    np.testing.assert_array_equal(goal, session.vertex_state(HELI_GOAL))
    by_state = session.plan(snapshot, _heli_start(session), goal, seed=0)
    assert by_state.path_edges == first.path_edges
    # A vertex start with the vertex goal of the precomputed tree uses the tree.
    tree = session.prior.trees[0]
    own = session.plan(snapshot, session.vertex_state(tree.start), tree.goal, seed=0)
    assert own.query == f"tree:{tree.name}"
    assert own.path_vertices[:1] in ((), (tree.start,))


def test_budgets_end_with_their_own_status(heli_prior: WorldPrior) -> None:
    session = QuerySession(heli_prior, name="heli", max_checks=1)
    snapshot = _heli_snapshot(session, 100)
    capped = session.plan(snapshot, _heli_start(session), HELI_GOAL)
    assert not capped.ok
    assert (capped.status, capped.cause) == (PlanStatus.BUDGET_EXHAUSTED, PlanCause.CHECK_BUDGET)
    assert len(capped.checks) == 1
    assert "check budget" in capped.message
    session.set_budgets(None, 1e-9)
    timed = session.plan(snapshot, _heli_start(session) + np.array([1.0, 0.0, 0.0, 0.0]), HELI_GOAL)
    assert not timed.ok
    assert (timed.status, timed.cause) == (PlanStatus.BUDGET_EXHAUSTED, PlanCause.TIME_BUDGET)
    assert "time budget" in timed.message
    with pytest.raises(ProblemError, match="max_checks"):
        session.set_budgets(0, None)
    with pytest.raises(ProblemError, match="time_budget_s"):
        QuerySession(heli_prior, name="heli", time_budget_s=-1.0)


def _edge_key(session: QuerySession, edge: int) -> object:
    """A graph edge's id, or a motion's states (motion ids differ between sessions)."""
    return edge if edge < session.prior.graph.num_edges else session.edge_states(edge).tobytes()


def test_an_improve_budget_publishes_a_shorter_path_checked_free_on_the_snapshot(
    heli_prior: WorldPrior,
) -> None:
    """Anytime improvement through the session: never longer, every edge checked free, the same first checks."""
    first_only = QuerySession(heli_prior, name="first")
    improving = QuerySession(heli_prior, name="improve", improve_budget=ImproveBudget(checks=60))
    assert first_only.improve_budget is None
    assert improving.improve_budget == ImproveBudget(checks=60)
    # From the lattice's start vertex: an off-graph start 30 m behind it joins most goals of this small
    # lattice by one motion, leaving nothing to improve.
    start, shorter = 0, 0
    for seed in range(100, 108):
        snapshot = _heli_snapshot(first_only, seed)
        checker = _independent_checker(first_only, snapshot)
        for goal in (HELI_GOAL, 9, 13):
            before = first_only.plan(snapshot, start, goal, seed=seed)
            after = improving.plan(_heli_snapshot(improving, seed), start, goal, seed=seed)
            assert after.ok == before.ok
            if not before.ok:
                assert after.improve_stop == ""
                assert after.improvements == 0
                continue
            # The same first path (same seed, same checks), then only improvement checks. Motion ids are
            # per session (given as motions are first checked), so motions compare by their states.
            n = len(before.checks)
            assert [(_edge_key(improving, c.edge), c.free, c.stage) for c in after.checks[:n]] == [
                (_edge_key(first_only, c.edge), c.free, c.stage) for c in before.checks
            ]
            assert {c.stage for c in after.checks[n:]} <= {"improve"}
            assert len(after.checks) - n <= 60
            assert after.improve_stop in ("optimal", "checks", "patience"), after.improve_stop
            assert after.first_cost == pytest.approx(before.cost)
            assert after.cost <= before.cost + 1e-9
            assert (after.improvements > 0) == (after.cost < before.cost - 1e-9)
            assert (after.stage == "improve") == (after.improvements > 0)
            assert before.improve_stop == ""
            assert "improvement" not in before.message
            assert f"improvement stopped: {after.improve_stop}" in after.message
            shorter += after.cost < before.cost - 1e-9
            # Every edge of the published path was checked free in this plan, and FCL agrees.
            log = {c.edge: c.free for c in after.checks}
            assert all(log.get(e) is True for e in after.path_edges)
            truth = {c.edge: bool(checker.check_motion(improving.edge_states(c.edge))) for c in after.checks}
            assert truth == log
            assert checker.check_motion(after.states)
            np.testing.assert_allclose(after.states[0], improving.vertex_state(start))
            np.testing.assert_allclose(after.states[-1], improving.vertex_state(goal))
    assert shorter >= 6  # measured: 12 of the 14 found plans get shorter (every improvement: optimal)
    # The plan's check cap bounds the improvement too: a cap that leaves no room for the checks the shorter
    # path needs keeps the first path (an int budget is checks).
    uncapped = QuerySession(heli_prior, name="uncapped", improve_budget=100)
    free_run = uncapped.plan(_heli_snapshot(uncapped, 102), start, 9, seed=102)
    assert free_run.ok
    assert free_run.improvements >= 1
    first = sum(c.stage != "improve" for c in free_run.checks)
    assert first < len(free_run.checks)  # the improvement needed checks of its own
    capped = QuerySession(heli_prior, name="capped", max_checks=len(free_run.checks) - 1, improve_budget=100)
    result = capped.plan(_heli_snapshot(capped, 102), start, 9, seed=102)
    assert result.ok
    assert result.improvements == 0
    assert len(result.checks) < len(free_run.checks)
    assert result.cost == pytest.approx(free_run.first_cost)
    with pytest.raises(ProblemError, match="ImproveBudget"):
        QuerySession(heli_prior, name="bad", improve_budget=1.5)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("start", "fragment"),
    [
        ([5000.0, 5000.0, 65.0, 0.0], "outside the lattice's horizontal extent x [0, 300] m"),
        ([350.0, 0.0, 500.0, 0.0], "outside the lattice's altitude band [40, 90] m"),
        ([0.0, float("nan"), 65.0, 0.0], "NaN"),
        ([0.0, 0.0, 65.0], "4 values"),  # a start needs its heading (only a goal may leave it free)
        (10**6, "outside the graph"),
    ],
)
def test_unreachable_or_malformed_starts_are_refused(
    heli_plan: tuple[QuerySession, MapSnapshot, SessionPlan], start: object, fragment: str
) -> None:
    session, snapshot, _ = heli_plan
    result = session.plan(snapshot, start, HELI_GOAL)  # type: ignore[arg-type]
    assert not result.ok
    assert result.status is PlanStatus.REFUSED
    assert fragment in result.message
    assert result.checks == ()
    assert result.path_edges == ()


def test_no_maps_is_refused(heli_prior: WorldPrior) -> None:
    session = QuerySession(heli_prior, name="heli")
    with pytest.raises(PlanningError, match="no maps"):
        session.plan(MapSnapshot(0), 0, HELI_GOAL)
    assert session.prepare(MapSnapshot(0)) == 0.0


def test_recheck_finds_a_box_on_a_motion_edge(
    heli_plan: tuple[QuerySession, MapSnapshot, SessionPlan],
) -> None:
    session, snapshot, result = heli_plan
    motion = result.path_edges[0]
    states = session.edge_states(motion)
    middle = states[states.shape[0] // 2, :3]
    far = snapshot.with_obstacles({**snapshot.obstacles, "probe/far": ((Box([5.0, 5.0, 5.0]), Pose([5000.0, 0, 0])),)})
    kept = recheck_plan(session, result.path_edges, snapshot, far)
    assert kept.kept
    assert kept.rechecked == ()
    new = snapshot.with_obstacles({**snapshot.obstacles, "probe/mid": ((Box([3.0, 3.0, 3.0]), Pose(middle)),)})
    assert motion in affected_edges(session, result.path_edges, snapshot, new)
    outcome = recheck_plan(session, result.path_edges, snapshot, new)
    assert not outcome.kept
    assert outcome.blocked == (motion,)
    assert "replanning" in outcome.reason
    assert not session.checker(new).check_motion(states)
    # Replan from where the robot is now (along the first graph edge) on the new map.
    along = session.edge_states(result.path_edges[1])
    robot = along[along.shape[0] // 2]
    replan = session.plan(new, robot, HELI_GOAL, seed=0)
    assert replan.ok
    np.testing.assert_allclose(replan.states[0], robot)
    assert _independent_checker(session, new).check_motion(replan.states)
    # Later plans never reuse the motion's id: it still names the same states.
    np.testing.assert_array_equal(session.edge_states(motion), states)
    with pytest.raises(PlanningError, match="nor motions the session knows"):
        recheck_plan(session, [10**6], snapshot, new)


def test_an_off_graph_goal_state_is_joined_too(
    heli_plan: tuple[QuerySession, MapSnapshot, SessionPlan],
) -> None:
    session, snapshot, _ = heli_plan
    goal = session.goal_state_from_position(session.vertex_state(HELI_GOAL)[:3] + np.array([20.0, 0.0, 0.0]), yaw=0.0)
    result = session.plan(snapshot, 0, goal, seed=0)
    assert result.ok
    assert result.path_vertices[0] == 0
    np.testing.assert_allclose(result.states[0], session.vertex_state(0))
    np.testing.assert_allclose(result.states[-1], goal)
    assert result.path_edges[-1] >= session.prior.graph.num_edges  # the goal is joined by a new motion
    assert _independent_checker(session, snapshot).check_motion(result.states)


def test_a_tree_files_own_query_asks_the_edges_of_its_trees_episode(tmp_path: Path) -> None:
    """A legacy tree file served through the session plans its query as DiRECt + BiSECt on its tree would."""
    bundle = load_tree_bundle(TREES / "heli_wires.npz")
    session = QuerySession(load_prior(save_tree(tmp_path / "tree.npz", bundle)), name="heli_wires")
    problem = bundle.problem
    root = bundle.tree.bias(0, alpha=bundle.alpha)
    context = PolicyContext(
        problem.library,
        problem.edge_costs,
        root,
        bundle.tree,
        7,
        eta=bundle.eta,
        alpha=bundle.alpha,
        pseudo_count=bundle.pseudo_count,
    )
    domain = session.domain
    assert isinstance(domain, HelicopterDomain)
    for seed in range(6):
        world = domain.make_world("wires", seed)
        parts = {name: ((shape, pose),) for name, shape, pose in world_parts(world, wire_segments=8)}
        snapshot = MapSnapshot(1, parts, world.terrain, session.margin)
        result = session.plan(snapshot, *own_query(session), seed=7)
        offline = run_episode(
            problem.library, problem.edge_costs, POLICIES["direct_bisect"](context), session.checker(snapshot)
        )
        asked = [(c.edge, c.free, c.stage) for c in result.checks]
        assert asked[: len(offline.checks)] == [(c.edge, c.free, c.stage) for c in offline.checks]
        assert result.query == "tree:heli_wires"
        if offline.success:  # the library proved a path: the session stops there too, with that path
            assert result.ok, result.message
            assert len(asked) == len(offline.checks)
            assert offline.path_edges is not None
            assert result.path_edges == tuple(int(e) for e in offline.path_edges)
            assert result.path_vertices[0] == domain.start
            assert result.path_vertices[-1] == domain.goal
            np.testing.assert_allclose(result.states[0], session.vertex_state(domain.start))
            np.testing.assert_allclose(result.states[-1], session.vertex_state(domain.goal))


def test_snapshots_with_the_same_terrain_share_its_collider_and_answer_alike() -> None:
    session = QuerySession(load_prior(TREES / "heli_wires.npz"), name="heli_wires")
    domain = session.domain
    assert isinstance(domain, HelicopterDomain)
    world = domain.make_world("wires", 4)
    obstacles = {f"p/{k}": ((shape, pose),) for k, (_, shape, pose) in enumerate(world_parts(world))}
    first = MapSnapshot(1, {}, world.terrain, session.margin).with_obstacles(obstacles)
    second = first.with_obstacles({})
    assert first.scene is not second.scene
    assert first.scene.terrain is second.scene.terrain
    assert first.cache.terrain_collider(world.terrain) is second.cache.terrain_collider(world.terrain)  # built once
    lone = Scene(margin=session.margin)
    lone.add_terrain(world.terrain)  # its own collider
    a, b = session.checker(second), session.domain.checker(lone)
    edges = session.library_edges()[:200]
    assert [a.check(int(e)) for e in edges] == [b.check(int(e)) for e in edges]
    checked_first = [session.checker(first).check(int(e)) for e in edges]
    assert checked_first != [a.check(int(e)) for e in edges]  # the obstacles matter, the shared terrain too


def test_a_legacy_tree_file_serves_its_own_query_only(tmp_path: Path) -> None:
    legacy = save_tree(tmp_path / "tree.npz", load_tree_bundle(TREES / "heli_wires.npz"))
    prior = load_prior(legacy)
    session = QuerySession(prior, name="heli_wires")
    tree = prior.trees[0]
    domain = session.domain
    assert isinstance(domain, HelicopterDomain)
    world = domain.make_world("wires", 2)
    parts = {name: ((shape, pose),) for name, shape, pose in world_parts(world, wire_segments=8)}
    snapshot = MapSnapshot(1, parts, world.terrain, session.margin)
    own = session.plan(snapshot, tree.start, tree.goal, seed=0)
    assert own.ok
    assert own.query == f"tree:{tree.name}"
    assert own.stage in ("tree", "bisect")
    other = session.plan(snapshot, tree.start, tree.goal - 1, seed=0)
    assert other.status is PlanStatus.REFUSED
    assert "drd build-tree" in other.message
    assert session.library_edges().size > 0


def test_a_prior_that_does_not_match_its_spec_is_refused(heli_prior: WorldPrior) -> None:
    lengths = heli_prior.graph.lengths.copy()
    lengths[0] += 3.0
    bad = dataclasses.replace(heli_prior, graph=dataclasses.replace(heli_prior.graph, lengths=lengths))
    with pytest.raises(PriorFileError, match="does not match"):
        QuerySession(bad, name="bad")
    with pytest.raises(TreeFileError, match="no domain spec"):
        QuerySession(dataclasses.replace(heli_prior, domain_spec={}), name="bare")
    with pytest.raises(PriorFileError, match="cannot be rebuilt"):
        QuerySession(dataclasses.replace(heli_prior, domain_spec={"lattice": "nonsense"}), name="junk")
    assert QuerySession(dataclasses.replace(heli_prior, trees=()), name="x").library_edges().size == 0


def test_pose_helpers_and_motion_ids() -> None:
    np.testing.assert_allclose(state_from_pose([1.0, 2.0, 3.0], 3 * math.pi), [1.0, 2.0, 3.0, -math.pi])
    half = math.sqrt(0.5)
    assert yaw_from_quaternion([0.0, 0.0, half, half]) == pytest.approx(math.pi / 2)
    with pytest.raises(PlanningError):
        state_from_pose([1.0, 2.0], 0.0)
    with pytest.raises(PlanningError):
        yaw_from_quaternion([0.0, 0.0, 0.0, 0.0])
    registry = MotionRegistry(10, capacity=2)
    a, b = np.zeros((2, 2)), np.ones((2, 2))
    assert registry.id_for(a) == 10
    assert registry.id_for(b) == 11
    assert registry.id_for(a.copy()) == 10
    assert registry.id_for(np.full((2, 2), 2.0)) == 12  # b, the least recently used, is forgotten
    assert registry.states(11) is None
    assert registry.is_motion_id(11)
    assert registry.id_for(b) == 13


# --------------------------------------------------------------------------------------------------
# Arm


@pytest.fixture(scope="module")
def arm(tmp_path_factory: pytest.TempPathFactory) -> tuple[QuerySession, MapSnapshot]:
    if not (SHARED_DATA / "panda" / "panda_spherized.urdf").is_file():
        pytest.skip("shared Panda model not present (set DRD_SHARED_DATA)")
    prior = _build_prior(tmp_path_factory.mktemp("arm"), "arm", "table_clutter", ARM_SPEC)
    session = QuerySession(prior, name="arm")
    domain = session.domain
    assert isinstance(domain, ArmDomain)
    world = domain.make_world("table_clutter", 5)
    snapshot = MapSnapshot(1, {o.name: ((o.shape, o.pose),) for o in world.obstacles}, None, session.margin)
    return session, snapshot


def _arm_start(session: QuerySession) -> np.ndarray:
    """A joint state off the roadmap, near the tree's start vertex."""
    return session.vertex_state(0) + np.array([0.1, -0.05, 0.0, 0.05, 0.0, 0.0, 0.0])


@pytest.mark.slow
def test_arm_plans_from_a_joint_state_to_an_end_effector_goal(arm: tuple[QuerySession, MapSnapshot]) -> None:
    session, snapshot = arm
    start = _arm_start(session)
    assert session.domain.plans_joint_goals
    assert len(session.joint_names) == 7
    checker = _independent_checker(session, snapshot)
    found = 0
    for vertex in ARM_GOALS:
        tool = session.positions(session.vertex_state(vertex))[0]
        goal = session.goal_state_from_position(tool + np.array([0.01, 0.0, 0.0]), snapshot=snapshot)
        np.testing.assert_array_equal(goal, session.vertex_state(vertex))
        result = session.plan(snapshot, start, goal, seed=0)
        assert result.status in (PlanStatus.FOUND, PlanStatus.NO_PATH)
        if not result.ok:
            continue
        found += 1
        np.testing.assert_allclose(result.states[0], start)
        np.testing.assert_allclose(result.states[-1], goal)
        assert result.path_edges[0] >= session.prior.graph.num_edges
        assert np.abs(np.diff(result.states, axis=0)).max() <= session.domain.resolution + 1e-9
        assert checker.check_motion(result.states)
        assert all(c.free for c in result.checks if c.edge in result.path_edges)
    assert found >= 2
    with pytest.raises(PlanningError, match=r"farther than the tolerance 0\.050 m"):
        session.goal_state_from_position([5.0, 5.0, 5.0])
    far = session.plan(snapshot, start + 10.0, ARM_GOALS[0])
    # one reason per cause
    assert far.status is PlanStatus.REFUSED
    assert "beyond the joint limits" in far.message


def test_arm_recheck_finds_a_box_on_a_motion_edge(arm: tuple[QuerySession, MapSnapshot]) -> None:
    session, snapshot = arm
    domain = session.domain
    assert isinstance(domain, ArmDomain)
    result = session.plan(snapshot, _arm_start(session), ARM_GOALS[0], seed=0)
    assert result.ok
    motion = result.path_edges[0]
    states = session.edge_states(motion)
    q_mid = states[states.shape[0] // 2]
    hand = domain.robot.fk.link_pose(q_mid, domain.robot.chain.tip_link)[0, :3, 3]
    new = snapshot.with_obstacles({**snapshot.obstacles, "probe/hand": ((Box([0.05, 0.05, 0.05]), Pose(hand)),)})
    assert not session.checker(new).check_motion(states)
    outcome = recheck_plan(session, result.path_edges, snapshot, new)
    assert motion in outcome.affected
    assert not outcome.kept
    assert outcome.blocked == (motion,)
    far = snapshot.with_obstacles({**snapshot.obstacles, "probe/far": ((Box([0.1, 0.1, 0.1]), Pose([3.0, 3.0, 0.5])),)})
    kept = recheck_plan(session, result.path_edges, snapshot, far)
    assert kept.kept
    assert kept.affected == ()


@pytest.mark.slow
def test_a_plan_that_grew_the_roadmap_is_verified_with_session_ids_for_its_new_edges() -> None:
    if not (SHARED_DATA / "panda" / "panda_spherized.urdf").is_file():
        pytest.skip("shared Panda model not present (set DRD_SHARED_DATA)")
    from conftest import REPO_ROOT

    session = QuerySession(load_prior(REPO_ROOT / "trees" / "arm_table_clutter.npz"), name="arm")
    domain = session.domain
    assert isinstance(domain, ArmDomain)
    world = domain.make_world("table_clutter", 3)  # the shipped roadmap has no free path 0 -> 1 here
    snapshot = MapSnapshot(1, {o.name: ((o.shape, o.pose),) for o in world.obstacles}, None, session.margin)
    start, goal = session.vertex_state(0), session.vertex_state(1)
    result = session.plan(snapshot, start, goal, seed=0)
    assert result.ok
    assert result.stage == "grow"
    num_edges = session.prior.graph.num_edges
    grown = [e for e in result.path_edges if e >= num_edges]
    assert grown
    assert all(session.motion_states(e) is not None for e in grown)
    assert all(c.free for c in result.checks if c.edge in result.path_edges)
    np.testing.assert_allclose(result.states[0], start)
    np.testing.assert_allclose(result.states[-1], goal)
    assert _independent_checker(session, snapshot).check_motion(result.states)
    again = session.plan(snapshot, start, goal, seed=0)  # the same answers, now from the snapshot's cache
    assert again.path_edges == result.path_edges
    assert all(c.cached for c in again.checks)
    # A map update on the grown part of the path reaches its motions like any edge (re-checks after updates).
    edge = grown[len(grown) // 2]
    middle = session.edge_states(edge)[len(session.edge_states(edge)) // 2]
    tool = domain.end_effector_positions(middle[None])[0]
    moved = MapSnapshot(2, {**snapshot.obstacles, "new": ((Box([0.1, 0.1, 0.1]), Pose(tool.tolist())),)}, None, 0.0)
    assert edge in affected_edges(session, result.path_edges, snapshot, moved)


def test_a_start_below_the_terrain_or_far_outside_gets_its_own_reason(heli_prior: WorldPrior) -> None:
    """Issue 33 item 7: one refusal ('outside the graph's reach') used to come back for four different causes."""
    session = QuerySession(heli_prior, name="heli")
    domain = session.domain
    assert isinstance(domain, HelicopterDomain)
    xs, ys = domain.frame.grid()
    hill = domain.frame.heightfield(np.full((ys.size, xs.size), 55.0))  # a plateau at 55 m under every level
    snapshot = MapSnapshot(1, {}, hill, session.margin)
    below = session.plan(snapshot, np.array([120.0, 10.0, 45.0, 0.0]), HELI_GOAL)
    assert below.status is PlanStatus.NO_PATH
    assert "the start state itself is blocked" in below.message
    assert "the terrain (below it, ground at 55.0 m)" in below.message
    far = session.plan(snapshot, np.array([4120.0, 10.0, 65.0, 0.0]), HELI_GOAL)
    assert far.status is PlanStatus.REFUSED
    assert "outside the lattice's horizontal extent" in far.message
    off_line = session.plan(
        _heli_snapshot(session, 101), session.vertex_state(0) + np.array([27.0, 2.0, 0.0, 0.0]), HELI_GOAL
    )
    assert off_line.status is not PlanStatus.REFUSED  # 2 m off a lattice line joins the lattice
