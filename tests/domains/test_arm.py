"""Arm domain: roadmap invariants, edge checks against independent sphere/box distances, the seam."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO_ROOT, SHARED_DATA
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components

from drd_planner.core.graph import ExplicitGraph
from drd_planner.domains.arm import DEFAULT_GOAL, DEFAULT_START, ArmDomain, ArmParams
from drd_planner.domains.arm_checker import ArmEdgeChecker, check_arm_edge
from drd_planner.domains.arm_params import SCENE_SPEC_DEFAULTS
from drd_planner.domains.arm_roadmap import EdgeSamples, statically_valid
from drd_planner.domains.arm_worlds import ArmWorld
from drd_planner.domains.base import EdgeChecker, domain_from_spec
from drd_planner.exceptions import PlanningError, ProblemError
from drd_planner.geometry.moveit_request import joint_vector, read_motion_plan_request
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Box, Pose

PANDA = SHARED_DATA / "panda"
SMALL = {"num_samples": 150, "k": 6, "seed": 3}


@pytest.fixture(scope="module")
def domain() -> ArmDomain:
    if not (PANDA / "panda_spherized.urdf").is_file():
        pytest.skip(f"shared Panda model {PANDA} not present (set DRD_SHARED_DATA)")
    built = domain_from_spec("arm", SMALL)
    assert isinstance(built, ArmDomain)
    return built


def sample_grid(domain: ArmDomain, edge: int) -> np.ndarray:
    """Every sample of an edge, end vertices included, in order along it (an independent construction)."""
    states = domain.graph.vertex_states
    assert states is not None
    u, v = domain.graph.edges[edge]
    steps = int(np.ceil(np.abs(states[v] - states[u]).max() / domain.resolution - 1e-9))
    t = np.linspace(0.0, 1.0, max(steps, 1) + 1)
    return states[u] + t[:, None] * (states[v] - states[u])


def brute_force_free(domain: ArmDomain, boxes: list[tuple[np.ndarray, np.ndarray]], margin: float) -> np.ndarray:
    """Free flags from exact sphere / axis-aligned box distances at every sample (numpy only, no FCL)."""
    radii = domain.robot.spheres.radii + margin
    free = np.ones(domain.graph.num_edges, dtype=bool)
    for e in range(domain.graph.num_edges):
        centres = domain.robot.sphere_centres(sample_grid(domain, e))
        for centre, half in boxes:
            outside = np.maximum(np.abs(centres - centre) - half, 0.0)
            if np.any(np.linalg.norm(outside, axis=2) <= radii):
                free[e] = False
                break
    return free


# --------------------------------------------------------------------------------------------------
# Roadmap


def test_roadmap_invariants(domain: ArmDomain) -> None:
    graph = domain.graph
    states = graph.vertex_states
    assert states is not None
    assert states.shape == (graph.num_vertices, 7)
    np.testing.assert_allclose(states[domain.start], DEFAULT_START)
    np.testing.assert_allclose(states[domain.goal], DEFAULT_GOAL)
    assert np.all(graph.edges[:, 0] < graph.edges[:, 1])
    np.testing.assert_allclose(
        graph.lengths, np.linalg.norm(states[graph.edges[:, 1]] - states[graph.edges[:, 0]], axis=1)
    )
    assert statically_valid(domain.robot, states).all()
    adjacency = coo_array((np.ones(graph.num_edges), (graph.edges[:, 0], graph.edges[:, 1])), shape=(len(states),) * 2)
    count, _ = connected_components(adjacency, directed=False)
    assert count == 1  # only the start's component is kept
    assert graph.num_edges > graph.num_vertices  # k-NN with k = 6 gives a well-connected graph


def test_roadmap_edges_are_statically_valid_at_every_sample(domain: ArmDomain) -> None:
    rng = np.random.default_rng(0)
    for e in rng.choice(domain.graph.num_edges, size=40, replace=False).tolist():
        assert statically_valid(domain.robot, sample_grid(domain, e)).all()


def test_edge_samples_resolution_and_bisection_order(domain: ArmDomain) -> None:
    samples = domain.samples
    assert isinstance(samples, EdgeSamples)
    states = domain.graph.vertex_states
    assert states is not None
    for e in range(0, domain.graph.num_edges, 37):
        fractions = samples.fractions[samples.offsets[e] : samples.offsets[e + 1]]
        grid = sample_grid(domain, e)
        assert fractions.shape[0] == grid.shape[0] - 2  # interior samples only
        along = np.sort(np.concatenate([[0.0], fractions, [1.0]]))
        u, v = domain.graph.edges[e]
        step = np.abs(np.diff(along)[:, None] * (states[v] - states[u])).max()
        assert step <= domain.resolution + 1e-12
        if fractions.size:
            assert fractions[0] == pytest.approx(along[(along.size - 1) // 2], abs=0.5 / along.size + 1e-12)


def test_roadmap_rejects_a_self_colliding_start() -> None:
    if not PANDA.is_dir():
        pytest.skip("shared Panda model not present")
    with pytest.raises(ProblemError, match="start configuration"):
        ArmDomain(ArmParams(start=(0.0, 0.3, 0.0, -3.0, 0.0, 0.3, 0.0), num_samples=20, k=4))


@pytest.mark.parametrize(
    ("spec", "says"),
    [
        (
            {"start": (0.0, 0.3, 0.0, -3.0, 0.0, 0.3, 0.0)},
            r"^start .*: self-colliding \(panda_link\d touches panda_link\d\): change start in the arm spec "
            r"\(--domain-spec\), or exclude the pair in the SRDF \(srdf_path\)$",
        ),
        (
            {"goal": (9.0, 0.7, 0.0, -1.6, 0.0, 2.4, 0.785)},
            r"^goal .*: outside the joint limits \(panda_joint1 = 9\.000 not in \[-2\.\d+, 2\.\d+\] rad\): change "
            r"goal in the arm spec \(--domain-spec\)$",
        ),
        (
            {"floor_z": 0.3},
            r"^start .*: below the floor \(a sphere of panda_link\d reaches down to z = 0\.\d+ m, the floor is at "
            r"floor_z = 0\.3 m\): set floor_z to 0\.\d+ or lower, or null \(no floor test\), in the arm spec",
        ),
    ],
)
def test_an_invalid_start_or_goal_says_which_check_failed(spec: dict[str, object], says: str) -> None:
    if not PANDA.is_dir():
        pytest.skip("shared Panda model not present")
    with pytest.raises(ProblemError) as info:
        ArmDomain.from_spec({"num_samples": 20, "k": 4, **spec})
    assert re.search(says, str(info.value)), str(info.value)
    assert "or below the floor" not in str(info.value)  # not the old "limits, self-colliding or floor"


# --------------------------------------------------------------------------------------------------
# Edge checks with known answers


def test_empty_world_has_every_edge_free(domain: ArmDomain) -> None:
    checker = domain.checker(ArmWorld(obstacles=(), model="empty"))
    assert checker.check_many(np.arange(domain.graph.num_edges)).all()


def test_box_around_the_base_blocks_everything(domain: ArmDomain) -> None:
    scene = Scene()
    scene.add(Box((0.05, 0.05, 0.05)), Pose((0.0, 0.0, 0.05)), name="in_base")
    checker = domain.checker(scene)
    assert not checker.check_many(np.arange(domain.graph.num_edges)).any()
    assert checker.check(0) is False


@pytest.mark.parametrize("margin", [0.0, 0.03])
def test_checks_match_independent_sphere_box_distances(domain: ArmDomain, margin: float) -> None:
    rng = np.random.default_rng(42)
    boxes = []
    scene = Scene(margin=margin)
    for i in range(5):
        centre = rng.uniform([0.2, -0.6, 0.1], [0.7, 0.6, 0.8])
        half = rng.uniform(0.03, 0.12, size=3)
        boxes.append((centre, half))
        scene.add(Box(2 * half), Pose(centre), name=f"box{i}")
    expected = brute_force_free(domain, boxes, margin)
    assert 0.05 < expected.mean() < 0.95  # a mix of free and blocked edges
    edges = np.arange(domain.graph.num_edges)
    many = domain.checker(scene).check_many(edges)
    assert np.array_equal(many, expected)
    single = domain.checker(scene)
    order = rng.permutation(edges)
    assert [single.check(int(e)) for e in order] == expected[order].tolist()


def test_check_and_check_many_agree_on_a_table_world(domain: ArmDomain) -> None:
    world = domain.make_world("table_clutter", 5)
    edges = np.arange(domain.graph.num_edges)
    many = domain.checker(world).check_many(edges[::-1])[::-1]
    one = domain.checker(world)
    assert [one.check(int(e)) for e in edges] == many.tolist()
    checker = domain.checker(world)
    assert isinstance(checker, EdgeChecker)
    assert checker.check_many(edges[:10]).dtype == np.bool_
    with pytest.raises(ProblemError, match="edge ids"):
        checker.check(domain.graph.num_edges)


def test_start_and_goal_are_free_in_every_sampled_world(domain: ArmDomain) -> None:
    states = domain.graph.vertex_states
    assert states is not None
    centres = domain.robot.sphere_centres(states[[domain.start, domain.goal]]).reshape(-1, 3)
    radii = np.tile(domain.robot.spheres.radii, 2)
    for model in domain.world_models:
        for seed in range(4):
            scene = domain.make_world(model, seed).to_scene(margin=domain.margin)
            assert not scene.spheres_collide(centres, radii)


# --------------------------------------------------------------------------------------------------
# Node-facing check from a URDF string


def test_check_arm_edge_from_urdf_strings(domain: ArmDomain) -> None:
    world = domain.make_world("clutter", 1)
    scene = world.to_scene()
    urdf = (PANDA / "panda.urdf").read_text()
    spheres = (PANDA / "panda_spherized.urdf").read_text()
    srdf = (PANDA / "panda.srdf").read_text()
    expected = domain.checker(world).check_many(np.arange(domain.graph.num_edges))
    for e in np.random.default_rng(1).choice(domain.graph.num_edges, size=12, replace=False).tolist():
        got = check_arm_edge(urdf=urdf, sphere_urdf=spheres, srdf=srdf, scene=scene, graph=domain.graph, edge=e)
        assert got == bool(expected[e])
    with pytest.raises(ProblemError, match="edge id"):
        check_arm_edge(urdf=spheres, scene=scene, graph=domain.graph, edge=-1)


def test_self_collision_option_blocks_a_self_colliding_edge(domain: ArmDomain) -> None:
    folded = np.array([0.0, 0.3, 0.0, -3.0, 0.0, 0.3, 0.0])
    ready = domain.robot.named_state("ready")
    graph = ExplicitGraph(np.array([[0, 1]]), np.ones(1), 2, vertex_states=np.stack([ready, folded]))
    scene = Scene()
    assert ArmEdgeChecker(robot=domain.robot, graph=graph, scene=scene).check(0) is True
    assert ArmEdgeChecker(robot=domain.robot, graph=graph, scene=scene, self_collision=True).check(0) is False


# --------------------------------------------------------------------------------------------------
# Domain seam


def test_spec_round_trip(domain: ArmDomain) -> None:
    spec = domain.spec()
    assert spec["num_samples"] == 150
    assert spec["resolution"] == 0.05
    again = domain_from_spec("arm", spec)
    assert again.spec() == spec
    assert np.array_equal(again.graph.edges, domain.graph.edges)
    assert again.graph.vertex_states is not None
    assert domain.graph.vertex_states is not None
    assert np.array_equal(again.graph.vertex_states, domain.graph.vertex_states)


def test_metadata_and_trajectories(domain: ArmDomain) -> None:
    meta = domain.check_metadata()
    assert meta["resolution_rad"] == 0.05
    assert meta["margin_m"] == 0.0
    assert meta["spheres"] == 59
    assert domain.edge_trajectories() is None
    assert domain.world_models == ("clutter", "table_clutter")


def test_online_members_kept_from_the_defaults_and_its_own(domain: ArmDomain) -> None:
    assert domain.vehicle_radius == 0.0
    assert domain.periodic_dims == ()
    assert domain.world_model_params("clutter") == {}
    assert domain.position_goals == "vertex"
    assert domain.has_sweep_model
    assert domain.joint_names == tuple(domain.robot.chain.joint_names)
    assert domain.sweep_robot(None) is None
    assert domain.sweep_robot(domain.robot) is None
    with pytest.raises(PlanningError, match="the arm domain matches goal positions to roadmap vertices"):
        domain.state_from_position([0.0, 0.0, 0.0], 0.0)


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ({"nodes": 3}, "unknown arm spec keys: nodes"),
        ({"resolution": 0.0}, "resolution must be finite and > 0"),
        ({"margin": -1.0}, "margin must be finite and >= 0"),
        ({"start": [0.0, 1.0]}, "7 joint values"),
        ({"urdf_path": "/nonexistent/robot.urdf"}, "cannot read robot description"),
    ],
)
def test_bad_specs(spec: dict[str, object], message: str) -> None:
    if not PANDA.is_dir():
        pytest.skip("shared Panda model not present")
    with pytest.raises(ProblemError, match=message):
        domain_from_spec("arm", {**SMALL, **spec})


def test_missing_shared_data_gives_a_clear_error(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("DRD_SHARED_DATA", str(tmp_path))
    with pytest.raises(ProblemError, match="DRD_SHARED_DATA"):
        ArmDomain(ArmParams(num_samples=10))


def test_world_from_moveit_scene(domain: ArmDomain) -> None:
    path = SHARED_DATA / "mbm" / "table_pick_panda" / "scene0001.yaml"
    if not path.is_file():
        pytest.skip(f"{path} not present")
    world = ArmDomain.world_from_scene(path)
    assert world.model == "moveit"
    assert len(world.obstacles) == 12
    free = domain.checker(world).check_many(np.arange(domain.graph.num_edges))
    assert free.shape == (domain.graph.num_edges,)
    assert 0 < free.sum() < free.size


def test_the_suggested_floor_z_accepts_the_start() -> None:
    if not PANDA.is_dir():
        pytest.skip("shared Panda model not present")
    with pytest.raises(ProblemError) as info:
        ArmDomain.from_spec({**SMALL, "floor_z": 0.3})
    found = re.search(r"set floor_z to (-?[\d.]+) or lower", str(info.value))
    assert found is not None, str(info.value)
    suggested = float(found.group(1))
    assert suggested < 0.3
    built = ArmDomain.from_spec({**SMALL, "floor_z": suggested})
    assert statically_valid(built.robot, built.graph.vertex_states, floor_z=suggested).all()
    with pytest.raises(ProblemError, match="below the floor"):  # 1 cm higher refuses the start or goal again
        ArmDomain.from_spec({**SMALL, "floor_z": suggested + 0.01})


def test_extra_states_spec_round_trip(domain: ArmDomain) -> None:
    states = domain.graph.vertex_states
    assert states is not None
    extras = (states[[20, 60]] - 0.01).tolist()
    built = domain_from_spec("arm", {**SMALL, "extra_states": extras})
    assert isinstance(built, ArmDomain)
    assert list(built.extra_vertices) == [2, 3]
    assert list(domain.extra_vertices) == []
    assert built.graph.vertex_states is not None
    np.testing.assert_array_equal(built.graph.vertex_states[2:4], extras)
    spec = built.spec()
    assert spec["extra_states"] == extras
    assert domain.spec()["extra_states"] == []
    again = domain_from_spec("arm", json.loads(json.dumps(spec)))
    assert again.spec() == spec
    assert np.array_equal(again.graph.edges, built.graph.edges)


def test_the_shipped_arm_prior_roadmap_is_rebuilt_byte_for_byte() -> None:
    path = REPO_ROOT / "trees" / "arm_table_clutter.npz"
    if not (path.is_file() and PANDA.is_dir()):
        pytest.skip(f"{path} or the shared Panda model not present")
    with np.load(path) as stored:
        header = json.loads(stored["header"].tobytes())
        edges, lengths, states = stored["edges"], stored["lengths"], stored["vertex_states"]
    assert "extra_states" not in header["domain_spec"]  # written before the key existed: the default applies
    built = domain_from_spec("arm", header["domain_spec"])
    assert built.graph.edges.tobytes() == edges.astype(np.int64).tobytes()
    assert built.graph.lengths.tobytes() == lengths.tobytes()
    assert built.graph.vertex_states is not None
    assert built.graph.vertex_states.tobytes() == states.tobytes()


def mbm_states(family: str) -> np.ndarray:
    """(N, 7) the distinct start and goal states of a MotionBenchMaker family's requests, in file order."""
    folder = SHARED_DATA / "mbm" / family
    if not (folder.is_dir() and PANDA.is_dir()):
        pytest.skip(f"{folder} or the shared Panda model not present")
    names = ArmDomain(ArmParams(num_samples=10)).joint_names
    rows = []
    for path in sorted(folder.glob("request*.yaml")):
        request = read_motion_plan_request(path)
        assert request.start is not None
        rows.append(joint_vector(request.start, names, where=path.name, allow_extra=True))
        rows.extend(joint_vector(goal, names, where=path.name) for goal in request.goals)
    _, first = np.unique(np.array(rows), axis=0, return_index=True)
    return np.array(rows)[np.sort(first)]


def test_box_panda_states_need_the_scene_floor_default() -> None:
    states = mbm_states("box_panda")
    spec = {"start": states[0].tolist(), "goal": states[1].tolist(), "extra_states": states[2:].tolist()}
    with pytest.raises(ProblemError) as info:
        ArmDomain.from_spec({**SMALL, **spec})
    text = str(info.value)
    assert text.startswith("goal configuration is not statically valid: below the floor (a sphere of panda_")
    found = re.search(r"floor_z = (-[\d.]+) passes the floor test of all (\d+) states", text)
    assert found is not None, text
    assert int(found.group(2)) == len(states) - 1  # every goal of box_panda reaches below the robot base
    for floor in (float(found.group(1)), SCENE_SPEC_DEFAULTS["floor_z"]):
        built = ArmDomain.from_spec({**SMALL, **spec, "floor_z": floor})
        assert built.graph.vertex_states is not None
        np.testing.assert_array_equal(built.graph.vertex_states[: len(states)], states)
        assert list(built.extra_vertices) == list(range(2, len(states)))


def test_the_arms_capabilities_say_the_node_plans_joint_goals_and_sends_a_trajectory(
    domain: ArmDomain,
) -> None:
    assert domain.plans_joint_goals
    assert domain.robot_state_topic == "joint_states"
    assert domain.publishes_joint_trajectory
    assert domain.needs_robot_description
    assert domain.state_columns == "joint angles, rad"
