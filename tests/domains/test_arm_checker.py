"""The arm's edge checker through the domain: free in an empty scene, blocked through a wall, motions too."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.domains.arm import ArmDomain
from drd_planner.domains.arm_checker import ArmEdgeChecker, SphereTest
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Box, Pose


@pytest.fixture(scope="module")
def domain(small_arm: ArmDomain) -> ArmDomain:
    return small_arm


def test_empty_scene_frees_everything_and_a_big_box_blocks_everything(domain: ArmDomain) -> None:
    edges = np.arange(domain.graph.num_edges)
    free = domain.scene_checker(Scene(margin=0.0))
    assert isinstance(free, ArmEdgeChecker)
    assert free.check_many(edges).all()
    walled = Scene(margin=0.0)
    walled.add(Box([4.0, 4.0, 4.0]), Pose([0.0, 0.0, 0.5]), name="all")
    blocked = domain.scene_checker(walled)
    assert not blocked.check_many(edges).any()
    assert not blocked.check(0)
    states = domain.graph.vertex_states
    assert states is not None
    assert free.check_motion(states[:2])
    assert not blocked.check_motion(states[:2])
    with pytest.raises(ProblemError, match="motion"):
        free.check_motion(np.zeros((2, 3)))


def test_sphere_model_answers_groups_as_their_rows(domain: ArmDomain) -> None:
    world = domain.make_world("clutter", 4)
    model = SphereTest(domain.robot, world.to_scene())
    edges = list(range(12))
    q = np.concatenate([domain.samples.configurations(domain.graph, e) for e in edges])
    owner = np.repeat(np.arange(len(edges)), [len(domain.samples.configurations(domain.graph, e)) for e in edges])
    per_row = model.groups_blocked(q, np.arange(len(q)), len(q))
    expected = [bool(per_row[owner == g].any()) for g in range(len(edges))]
    assert 0 < sum(expected) < len(edges)  # some of each
    assert model.groups_blocked(q, owner, len(edges)).tolist() == expected
    alone = [
        bool(model.groups_blocked(q[owner == g], np.zeros(int(np.sum(owner == g)), dtype=np.int64), 1)[0])
        for g in range(len(edges))
    ]
    assert alone == expected
    checker = domain.checker(world)
    assert isinstance(checker.model, SphereTest)
    interiors_free = [not b for b in expected]
    ends_free = checker.check_many(edges)
    assert all(
        f <= i for f, i in zip(ends_free.tolist(), interiors_free, strict=True)
    )  # interior blocked: edge blocked


def test_motions_off_the_roadmap_obey_the_static_rules(domain: ArmDomain) -> None:
    free = domain.scene_checker(Scene(margin=0.0))
    robot = domain.robot
    rng = np.random.default_rng(0)
    q = robot.lower + rng.random((4000, robot.dof)) * (robot.upper - robot.lower)
    ok = robot.within_limits(q) & ~robot.self_collision(q)
    colliding = q[robot.within_limits(q) & robot.self_collision(q)][0]
    start = np.asarray(domain.params.start, dtype=np.float64)
    # A motion through a self-colliding configuration is blocked in an empty scene (it was not, before).
    assert not free.check_motion(np.array([start, colliding]))
    assert not free.check_motion(colliding[None])
    beyond = start.copy()
    beyond[0] = robot.upper[0] + 0.1
    assert not free.check_motion(np.array([start, beyond]))  # joint limits
    assert free.check_motion(q[ok][:1])
    assert domain.params.floor_z == 0.0
    moving = robot.spheres.frame_index > 0
    bottoms = (robot.sphere_centres(q)[:, moving, 2] - robot.spheres.radii[moving]).min(axis=1)
    under = q[ok & (bottoms < -0.05)][0]  # valid but for the floor
    assert not free.check_motion(under[None])
    assert "below the floor" in free.explain_motion(under[None])


def test_explain_motion_names_what_blocks_the_first_blocked_sample(domain: ArmDomain) -> None:
    states = domain.graph.vertex_states
    assert states is not None
    goal = np.asarray(domain.params.goal, dtype=np.float64)
    scene = Scene(margin=0.0)
    scene.add(Box([0.15, 0.15, 0.15]), Pose(domain.end_effector_positions(goal[None])[0].tolist()), name="can")
    checker = domain.scene_checker(scene)
    motion = np.linspace(np.asarray(domain.params.start, dtype=np.float64), goal, 21)
    assert not checker.check_motion(motion)
    why = checker.explain_motion(motion)
    # the goal end
    assert why.startswith("scene object 'can' (panda_")
    assert why.endswith("at sample 21 of 21")
    assert checker.explain_motion(goal[None]).startswith("scene object 'can'")
    assert domain.scene_checker(Scene(margin=0.0)).explain_motion(motion) == ""
