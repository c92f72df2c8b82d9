"""The arm's mesh collision model through the domain: spec choice, brute-force agreement, order, margin."""

from __future__ import annotations

import shutil
from pathlib import Path

import fcl
import numpy as np
import pytest
from conftest import SHARED_DATA, SMALL_ARM_SPEC

from drd_planner.domains.arm import ArmDomain
from drd_planner.domains.arm_checker import ArmEdgeChecker, SphereTest
from drd_planner.domains.arm_mesh_checker import mesh_sweep_growth
from drd_planner.domains.base import domain_from_spec
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.fcl_queries import pair_distance
from drd_planner.geometry.mesh_collider import MeshCollider
from drd_planner.geometry.robot import RobotModel
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Box, Pose, make_fcl_geometry

PANDA = SHARED_DATA / "panda"
SMALL = SMALL_ARM_SPEC


@pytest.fixture(scope="module")
def meshes(small_arm_meshes: ArmDomain) -> ArmDomain:
    return small_arm_meshes


def mesh_model(checker: ArmEdgeChecker) -> MeshCollider:
    assert isinstance(checker.model, MeshCollider)
    return checker.model


def edge_configurations(domain: ArmDomain, edge: int) -> np.ndarray:
    """(n, D) both end vertices, then the interior samples in bisection order."""
    states = domain.graph.vertex_states
    assert states is not None
    u, v = domain.graph.edges[edge]
    return np.concatenate([states[[u, v]], domain.samples.configurations(domain.graph, edge)])


def brute_force_free(domain: ArmDomain, world_obstacles: list[fcl.CollisionObject], edge: int) -> bool:
    """Every element at every sample against every obstacle, one FCL pair at a time (no prefilter)."""
    placement = mesh_model(domain.checker(Scene())).placement
    poses = placement.poses(edge_configurations(domain, edge))
    for sample in poses:
        for part, pose in enumerate(sample):
            geometry = placement.meshes.parts[part].geometry
            obj = fcl.CollisionObject(geometry, fcl.Transform(pose[:3, :3], pose[:3, 3]))
            for other in world_obstacles:
                if fcl.collide(obj, other, fcl.CollisionRequest(), fcl.CollisionResult()) > 0:
                    return False
    return True


def test_the_spec_chooses_the_collision_model(small_arm: ArmDomain, meshes: ArmDomain) -> None:
    assert isinstance(small_arm.checker(Scene()).model, SphereTest)
    assert isinstance(meshes.scene_checker(Scene()).model, MeshCollider)
    assert small_arm.check_metadata()["collision_model"] == "spheres"
    meta = meshes.check_metadata()
    assert meta["collision_model"] == "meshes"
    assert meta["mesh_elements"] == 11
    assert meta["mesh_triangles"] > 3000
    assert "panda_hand" in meta["mesh_links"]
    assert meshes.spec()["collision_model"] == "meshes"
    assert np.array_equal(meshes.graph.edges, small_arm.graph.edges)  # the same roadmap
    # Every checker shares one set of BVH models.
    one, two = mesh_model(meshes.checker(Scene())), mesh_model(meshes.checker(Scene()))
    assert one.placement.meshes is two.placement.meshes
    with pytest.raises(ProblemError, match="collision_model must be one of spheres, meshes"):
        domain_from_spec("arm", {**SMALL, "collision_model": "capsules"})


def test_mesh_checks_match_a_brute_force_fcl_check(meshes: ArmDomain) -> None:
    world = meshes.make_world("clutter", 4)
    obstacles = [fcl.CollisionObject(make_fcl_geometry(o.shape), o.pose.to_fcl()) for o in world.obstacles]
    checker = meshes.checker(world)
    outcomes = checker.check_many(np.arange(meshes.graph.num_edges))
    assert 0 < outcomes.sum() < outcomes.size  # some edges of each kind
    rng = np.random.default_rng(0)
    chosen = np.concatenate(
        [
            rng.choice(np.flatnonzero(outcomes), 4, replace=False),
            rng.choice(np.flatnonzero(~outcomes), 4, replace=False),
        ]
    )
    for e in chosen.tolist():
        assert brute_force_free(meshes, obstacles, e) == bool(outcomes[e]), e
        assert meshes.checker(world).check(e) == bool(outcomes[e])


class RecordingModel:
    """The real mesh model, recording what it is asked (configurations and groups)."""

    def __init__(self, inner: MeshCollider) -> None:
        self.inner = inner
        self.calls: list[tuple[np.ndarray, np.ndarray, int]] = []

    def base_free(self) -> bool:
        return self.inner.base_free()

    def groups_blocked(self, q: np.ndarray, owner: np.ndarray, count: int) -> np.ndarray:
        self.calls.append((q.copy(), owner.copy(), count))
        return self.inner.groups_blocked(q, owner, count)


def test_end_vertices_first_then_bisection_order_with_early_exit(meshes: ArmDomain) -> None:
    world = meshes.make_world("clutter", 4)
    reference = meshes.checker(world)
    free = reference.check_many(np.arange(meshes.graph.num_edges))
    for e in np.flatnonzero(~free).tolist():
        q = edge_configurations(meshes, e)
        per_row = mesh_model(meshes.checker(world)).groups_blocked(q, np.arange(len(q)), len(q))
        first = int(np.argmax(per_row))
        if first >= 2 and not per_row[first + 1 :].all():  # blocked inside, with free samples after it
            break
    else:
        pytest.fail("no edge blocked in its interior before a free sample")
    scene = world.to_scene(margin=meshes.margin)
    recording = RecordingModel(mesh_model(meshes.checker(scene)))
    checker = ArmEdgeChecker(
        robot=meshes.robot,
        graph=meshes.graph,
        scene=scene,
        samples=meshes.samples,
        model_for=lambda _scene: recording,
    )
    assert checker.check(e) is False
    (ends, ends_owner, ends_count), (inner, inner_owner, inner_count) = recording.calls
    np.testing.assert_array_equal(ends, q[:2])  # both end vertices first, each its own group
    assert ends_owner.tolist() == [0, 1]
    assert ends_count == 2
    np.testing.assert_array_equal(inner, q[2:])  # then the interior, as one group, in bisection order
    assert inner_count == 1
    assert not inner_owner.any()
    stopped = recording.inner.queries
    everything = mesh_model(meshes.checker(scene))
    everything.groups_blocked(q, np.arange(len(q)), len(q))
    assert stopped < everything.queries  # the samples after the first blocked one were never decided


def min_distance(domain: ArmDomain, edge: int, obstacle: fcl.CollisionObject) -> float:
    """The smallest FCL distance (m) from any element at any sample of ``edge`` to ``obstacle``."""
    placement = mesh_model(domain.checker(Scene())).placement
    best = np.inf
    for sample in placement.poses(edge_configurations(domain, edge)):
        for part, pose in enumerate(sample):
            obj = fcl.CollisionObject(placement.meshes.parts[part].geometry, fcl.Transform(pose[:3, :3], pose[:3, 3]))
            best = min(best, pair_distance(obj, obstacle))
    return float(best)


def test_margin_blocks_edges_that_pass_closer_than_it(meshes: ArmDomain) -> None:
    world = meshes.make_world("table_clutter", 2)
    exact = meshes.checker(world.to_scene(margin=0.0)).check_many(np.arange(meshes.graph.num_edges))
    wide = meshes.checker(world.to_scene(margin=0.03)).check_many(np.arange(meshes.graph.num_edges))
    # a margin only blocks more
    assert not np.any(wide & ~exact)
    assert np.sum(exact & ~wide) > 0
    assert mesh_model(meshes.checker(world.to_scene(margin=0.03))).obstacles.margin == 0.03
    e = int(np.flatnonzero(exact)[0])
    tool = meshes.end_effector_positions(edge_configurations(meshes, e)[2:3])[0]
    box = Box([0.04, 0.04, 0.04])
    for offset in ([0, 0, -0.07], [0.1, 0, 0], [-0.1, 0, 0], [0, 0.1, 0], [0, -0.1, 0]):
        where = Pose(tool + np.array(offset))
        gap = min_distance(meshes, e, fcl.CollisionObject(make_fcl_geometry(box), where.to_fcl()))
        if 0.005 < gap < 0.2:  # near the swept arm, not touching it
            break
    else:
        pytest.fail("no box position near the edge's sweep")
    outcomes = []
    for margin in (0.0, 0.95 * gap, 1.05 * gap):
        scene = Scene(margin=margin)
        scene.add(box, where, name="near")
        outcomes.append(meshes.scene_checker(scene).check(e))
    assert outcomes == [True, True, False]


def test_results_are_deterministic_in_any_order(meshes: ArmDomain) -> None:
    world = meshes.make_world("table_clutter", 5)
    edges = np.arange(meshes.graph.num_edges)
    first = meshes.checker(world).check_many(edges)
    second = meshes.checker(world).check_many(edges[::-1])[::-1]
    one_by_one = meshes.checker(world)
    third = np.array([one_by_one.check(e) for e in edges[::-1].tolist()])[::-1]
    np.testing.assert_array_equal(first, second)
    np.testing.assert_array_equal(first, third)


def test_another_robot_model_places_the_same_meshes(meshes: ArmDomain) -> None:
    texts = [(PANDA / name).read_text() for name in ("panda.urdf", "panda_spherized.urdf", "panda.srdf")]
    other = RobotModel.from_urdf(texts[0], sphere_urdf=texts[1], srdf=texts[2])
    assert other is not meshes.robot
    world = meshes.make_world("table_clutter", 5)
    theirs = meshes.checker(world, robot=other)
    assert theirs.self_collision
    assert mesh_model(theirs).placement.robot is other
    edges = np.arange(meshes.graph.num_edges)
    np.testing.assert_array_equal(theirs.check_many(edges), meshes.checker(world).check_many(edges))


def test_missing_meshes_name_the_file_and_the_parameter(tmp_path: Path, meshes: ArmDomain) -> None:
    shutil.copy(PANDA / "panda.urdf", tmp_path / "panda.urdf")
    spec = {
        **SMALL,
        "urdf_path": str(tmp_path / "panda.urdf"),
        "sphere_urdf_path": str(PANDA / "panda_spherized.urdf"),
        "srdf_path": str(PANDA / "panda.srdf"),
    }
    domain = domain_from_spec("arm", {**spec, "collision_model": "meshes"})
    with pytest.raises(
        ProblemError, match=r"collision mesh 'package://meshes/collision/link0.obj' not found.*urdf_path"
    ):
        domain.checker(Scene())
    assert domain_from_spec("arm", spec).checker(Scene()).check(0)  # the sphere model needs no mesh


def test_sweep_growth_is_computed_once_and_contains_the_meshes(meshes: ArmDomain) -> None:
    model = mesh_model(meshes.checker(Scene()))
    growth = mesh_sweep_growth(meshes.robot, model.placement.meshes)
    assert mesh_sweep_growth(meshes.robot, model.placement.meshes) is growth
    # the base sticks out most
    assert growth.shape == (meshes.robot.spheres.count,)
    assert growth.max() > 0.05
    centres = meshes.robot.sphere_centres(edge_configurations(meshes, 0))  # (n, S, 3)
    placement = model.placement
    poses = placement.poses(edge_configurations(meshes, 0))
    for n in range(poses.shape[0]):
        for p in range(placement.count):
            points = placement.world_vertices(poses[n, p], p)
            gaps = np.linalg.norm(points[:, None] - centres[n], axis=2) - meshes.robot.spheres.radii - growth
            assert gaps.min(axis=1).max() <= 1e-9
