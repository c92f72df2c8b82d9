"""The arm's statically valid configurations and why a query state is refused (limits, degrees, self-collision)."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.domains.arm import ArmDomain
from drd_planner.domains.arm_roadmap import statically_valid
from drd_planner.domains.arm_sampler import ArmStateSampler, arm_state_sampler, looks_like_degrees
from drd_planner.planner.state_sampler import StateSampler

#: A Panda configuration in degrees (the home pose: 0, -45, 0, -135, 0, 90, 45).
HOME_DEG = np.array([0.0, -45.0, 0.0, -135.0, 0.0, 90.0, 45.0])


@pytest.fixture(scope="module")
def sampler(small_arm: ArmDomain) -> ArmStateSampler:
    built = arm_state_sampler(small_arm.spec())
    # the loader's one model
    assert isinstance(built, StateSampler)
    assert built.robot is small_arm.robot
    return built


def test_valid_is_the_roadmaps_static_test(sampler: ArmStateSampler, small_arm: ArmDomain) -> None:
    rng = np.random.default_rng(1)
    q = sampler.lower + rng.random((500, 7)) * (sampler.upper - sampler.lower)
    q[0, 0] = 10.0
    expected = statically_valid(small_arm.robot, q, floor_z=small_arm.params.floor_z)
    np.testing.assert_array_equal(sampler.valid(q), expected)
    assert not expected[0]
    assert expected.any()
    assert not expected.all()
    assert sampler.valid(np.zeros((0, 7))).shape == (0,)


def test_joint_values_beyond_the_limits_are_refused_with_limits_and_unit(sampler: ArmStateSampler) -> None:
    q = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 3.5])
    why = sampler.refusal(q, "goal")
    assert why == "goal joint values are beyond the joint limits: panda_joint7 = 3.500 not in [-2.967, 2.967] (rad)"


def test_values_that_look_like_degrees_are_said_to(sampler: ArmStateSampler) -> None:
    assert looks_like_degrees(sampler.robot, HOME_DEG)
    why = sampler.refusal(HOME_DEG, "start")
    assert why is not None
    assert why.startswith("start joint values are beyond the joint limits: panda_joint2 = -45.000")
    assert "look like degrees: in radians they are [0.0, -0.7854, 0.0, -2.3562, 0.0, 1.5708, 0.7854]" in why
    assert not looks_like_degrees(sampler.robot, np.full(7, 30.0))  # beyond the limits in degrees too


def test_self_colliding_and_valid_states(sampler: ArmStateSampler) -> None:
    robot = sampler.robot
    rng = np.random.default_rng(0)
    q = robot.lower + rng.random((4000, 7)) * (robot.upper - robot.lower)
    colliding = q[robot.self_collision(q) & robot.within_limits(q)][0]
    why = sampler.refusal(colliding, "start")
    assert why is not None
    assert "is not valid for this prior's roadmap: self-collision (panda_" in why
    assert sampler.refusal(np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]), "start") is None
    assert "has 3 joint values; the arm has 7" in str(sampler.refusal(np.zeros(3), "goal"))
