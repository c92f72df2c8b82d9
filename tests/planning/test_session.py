"""The ROS-free planning session: lazy cached checks, the safety invariant, same seed same checks."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from drd_planner.cli.main import main
from drd_planner.core.episode import run_episode
from drd_planner.core.policies import POLICIES
from drd_planner.data.tree_file import TreeBundle
from drd_planner.domains.helicopter import HelicopterDomain
from drd_planner.domains.helicopter_worlds import world_parts
from drd_planner.exceptions import PlanningError, TreeFileError
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.terrain import Heightfield
from drd_planner.planner import load_tree_bundle
from drd_planner.planning.map_state import MapSnapshot, changed_parts
from drd_planner.planning.session import PlanningSession

#: Worlds of the test tree with a free library path, and worlds where every library path is blocked.
PATH_SEEDS = (100, 102, 104, 106, 107, 109)
BLOCKED_SEEDS = (101, 103)

SPEC = '{"lattice": {"x_range": [0.0, 300.0], "y_range": [-100.0, 100.0], "goal": [300.0, 0.0]}}'


@pytest.fixture(scope="module")
def bundle(tmp_path_factory: pytest.TempPathFactory) -> TreeBundle:
    folder = tmp_path_factory.mktemp("heli")
    dataset, tree = folder / "heli.npz", folder / "tree.npz"
    argv = ["build-dataset", "--domain", "helicopter", "--world-model", "wires", "--worlds", "40"]
    argv += ["--seed", "3", "--out", str(dataset), "--workers", "1", "--domain-spec", SPEC]
    assert main(argv) == 0
    assert main(["build-tree", "--dataset", str(dataset), "--out", str(tree), "--eta", "0.2", "--kappa", "10"]) == 0
    return load_tree_bundle(tree, expected_domain="helicopter")


def _snapshot(session: PlanningSession, seed: int) -> MapSnapshot:
    domain = session.domain
    assert isinstance(domain, HelicopterDomain)
    world = domain.make_world("wires", seed)
    parts = {name: ((shape, pose),) for name, shape, pose in world_parts(world, wire_segments=8)}
    return MapSnapshot(1, parts, world.terrain, session.margin)


def test_plan_is_verified_and_matches_the_offline_episode(bundle: TreeBundle) -> None:
    session = PlanningSession(bundle, name="wires")
    for seed in (*PATH_SEEDS, *BLOCKED_SEEDS):
        snapshot = _snapshot(session, seed)
        result = session.plan(snapshot, seed=7)
        # The same policy on the same scene through the plain runner asks for the same edges.
        ctx = dataclasses.replace(session._context, seed=7)
        offline = run_episode(
            bundle.problem.library,
            bundle.problem.edge_costs,
            POLICIES["direct_bisect"](ctx),
            session.checker(snapshot),
        )
        assert [(c.edge, c.free, c.stage) for c in offline.checks] == [(c.edge, c.free, c.stage) for c in result.checks]
        checked = {c.edge: c.free for c in result.checks}
        if seed in BLOCKED_SEEDS:  # every library path is blocked in these worlds
            assert not result.ok, result.message
            assert result.status == "no_free_path", result.message
            assert result.path_edges == ()
            assert "checks" in result.message
            continue
        assert result.ok, f"seed {seed}: {result.message}"  # these worlds have a free library path
        assert result.status == "path_found"
        assert result.path_edges
        assert all(checked.get(e) is True for e in result.path_edges)
        vertices = result.path_vertices
        assert vertices[0] == session.domain.start
        assert vertices[-1] == session.domain.goal
        edges = session.domain.graph.edges
        for k, e in enumerate(result.path_edges):  # each edge joins consecutive path vertices
            assert tuple(int(v) for v in edges[e]) == (vertices[k], vertices[k + 1])
        assert result.states.shape[1] == 4
        assert result.states.shape[0] > len(result.path_edges)
        np.testing.assert_allclose(result.states[0], session.vertex_state(vertices[0]))
        np.testing.assert_allclose(result.states[-1], session.vertex_state(vertices[-1]))


def test_checks_are_cached_per_map_version(bundle: TreeBundle) -> None:
    session = PlanningSession(bundle, name="wires")
    snapshot = _snapshot(session, 101)
    first = session.plan(snapshot, seed=1)
    again = session.plan(snapshot, seed=1)
    assert [c.edge for c in again.checks] == [c.edge for c in first.checks]
    assert not any(c.cached for c in first.checks)
    assert all(c.cached and c.check_ms == 0.0 for c in again.checks)
    moved = snapshot.with_obstacles(snapshot.obstacles)
    third = session.plan(moved, seed=1)
    assert not any(c.cached for c in third.checks)
    assert third.map_version == snapshot.version + 1


def test_empty_map_is_refused(bundle: TreeBundle) -> None:
    session = PlanningSession(bundle, name="wires")
    with pytest.raises(PlanningError, match="no maps"):
        session.plan(MapSnapshot(0))


def test_goal_matching(bundle: TreeBundle) -> None:
    session = PlanningSession(bundle, name="wires", goal_tolerance=1.0)
    goal = session.goal_state
    assert session.matches_goal(goal[:3])
    assert session.matches_goal(goal[:3] + 0.5)
    assert not session.matches_goal(goal[:3] + np.array([5.0, 0.0, 0.0]))


def test_tree_whose_graph_does_not_match_its_spec_is_refused(bundle: TreeBundle, tmp_path: Path) -> None:
    graph = bundle.problem.graph
    assert graph is not None
    lengths = graph.lengths.copy()
    lengths[0] += 3.0
    bad_graph = dataclasses.replace(graph, lengths=lengths) if dataclasses.is_dataclass(graph) else None
    if bad_graph is None:
        pytest.skip("graph is not a dataclass")
    bad = dataclasses.replace(bundle, problem=dataclasses.replace(bundle.problem, graph=bad_graph))
    with pytest.raises(TreeFileError, match="does not match"):
        PlanningSession(bad, name="bad")
    no_spec = dataclasses.replace(bundle, problem=dataclasses.replace(bundle.problem, metadata={}))
    with pytest.raises(TreeFileError, match="no domain spec"):
        PlanningSession(no_spec, name="bare")


def test_changed_parts(bundle: TreeBundle) -> None:
    session = PlanningSession(bundle, name="wires")
    snapshot = _snapshot(session, 101)
    same = snapshot.with_obstacles(dict(snapshot.obstacles))
    assert changed_parts(snapshot, same) == []
    key = sorted(snapshot.obstacles)[0]
    fewer = dict(snapshot.obstacles)
    removed = fewer.pop(key)
    assert changed_parts(snapshot, snapshot.with_obstacles(fewer)) == list(removed)
    terrain = snapshot.terrain
    assert terrain is not None
    copy = Heightfield(terrain.origin, terrain.cell_size, terrain.heights.copy())
    assert changed_parts(snapshot, snapshot.with_terrain(copy)) == []  # equal heights: nothing changed
    raised = Heightfield(terrain.origin, terrain.cell_size, terrain.heights + 1.0)
    assert changed_parts(snapshot, snapshot.with_terrain(raised)) is None  # terrain changed: check all


def test_snapshots_with_the_same_terrain_share_its_collider_and_answer_alike() -> None:
    bundle = load_tree_bundle(Path(__file__).resolve().parents[2] / "trees" / "heli_wires.npz")
    session = PlanningSession(bundle)
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
    edges = session.bundle.problem.library.library_edges[:200]
    assert [a.check(int(e)) for e in edges] == [b.check(int(e)) for e in edges]
    checked_first = [session.checker(first).check(int(e)) for e in edges]
    assert checked_first != [a.check(int(e)) for e in edges]  # the obstacles matter, the shared terrain too
