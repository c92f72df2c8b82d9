"""What blocks an arm configuration: the scene object (and link) for spheres and meshes, or the robot's own rules."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.domains.arm import ArmDomain
from drd_planner.domains.arm_explain import explain_base, explain_configuration, objects_alone, static_reason
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Box, Pose


def _scene_around_the_hand(domain: ArmDomain, q: np.ndarray) -> Scene:
    scene = Scene(margin=0.0)
    hand = domain.end_effector_positions(q[None])[0]
    scene.add(Box([0.15, 0.15, 0.15]), Pose(hand.tolist()), name="can")
    scene.add(Box([0.1, 0.1, 0.1]), Pose([-0.8, -0.8, 0.05]), name="far_away")
    return scene


@pytest.mark.parametrize("fixture", ["small_arm", "small_arm_meshes"])
def test_the_object_that_blocks_a_configuration_is_named_with_its_link(
    fixture: str, request: pytest.FixtureRequest
) -> None:
    domain: ArmDomain = request.getfixturevalue(fixture)
    q = np.asarray(domain.params.goal, dtype=np.float64)
    scene = _scene_around_the_hand(domain, q)
    checker = domain.checker(scene)
    why = explain_configuration(domain.robot, scene, q, model_for=checker.model_for, floor_z=None)
    assert why.startswith("scene object 'can' (panda_")
    assert "far_away" not in why
    free = np.asarray(domain.params.start, dtype=np.float64)
    assert explain_configuration(domain.robot, Scene(margin=0.0), free, model_for=checker.model_for, floor_z=None) == ""
    assert scene.names == ("can", "far_away")  # explaining leaves the scene as it was
    assert [name for name, alone in objects_alone(scene) if alone.names == (name,)] == ["can", "far_away"]


def test_the_robots_own_rules_come_first(small_arm: ArmDomain) -> None:
    robot = small_arm.robot
    q = np.asarray(small_arm.params.start, dtype=np.float64)
    assert static_reason(robot, q, floor_z=0.0) == ""
    beyond = q.copy()
    beyond[0] = 9.0
    assert static_reason(robot, beyond, floor_z=None).startswith(
        "outside the joint limits (panda_joint1 = 9.000 not in"
    )
    under = static_reason(robot, q, floor_z=2.0)  # a floor above the whole arm
    assert under.startswith("below the floor (panda_")
    assert "floor_z = 2 m" in under


def test_self_collision_is_named(small_arm: ArmDomain) -> None:
    robot = small_arm.robot
    rng = np.random.default_rng(0)
    samples = robot.lower + rng.random((4000, robot.dof)) * (robot.upper - robot.lower)
    colliding = samples[robot.self_collision(samples)]
    assert colliding.shape[0] > 0
    why = static_reason(robot, colliding[0], floor_z=None)
    assert why.startswith("self-collision (panda_")
    assert " touches panda_" in why


def test_the_fixed_base_names_what_it_meets(small_arm: ArmDomain) -> None:
    scene = Scene(margin=0.0)
    scene.add(Box([0.3, 0.3, 0.3]), Pose([0.0, 0.0, 0.05]), name="pedestal")
    checker = small_arm.checker(scene)
    assert explain_base(scene, model_for=checker.model_for) == "the robot's fixed base meets scene object 'pedestal'"
    assert explain_base(Scene(margin=0.0), model_for=checker.model_for) == ""
