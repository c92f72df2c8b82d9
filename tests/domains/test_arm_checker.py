"""The arm's edge checker through the domain: free in an empty scene, blocked through a wall, motions too."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.domains.arm import ArmDomain
from drd_planner.domains.arm_checker import ArmEdgeChecker
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Box, Pose


@pytest.fixture(scope="module")
def domain(small_arm: ArmDomain) -> ArmDomain:
    return small_arm


def test_empty_scene_frees_everything_and_a_big_box_blocks_everything(domain: ArmDomain) -> None:
    edges = np.arange(domain.graph.num_edges)
    free = domain.scene_checker(Scene(margin=0.0))
    assert isinstance(free, ArmEdgeChecker) and free.check_many(edges).all()
    walled = Scene(margin=0.0)
    walled.add(Box([4.0, 4.0, 4.0]), Pose([0.0, 0.0, 0.5]), name="all")
    blocked = domain.scene_checker(walled)
    assert not blocked.check_many(edges).any() and not blocked.check(0)
    states = domain.graph.vertex_states
    assert states is not None
    assert free.check_motion(states[:2]) and not blocked.check_motion(states[:2])
    with pytest.raises(ProblemError, match="motion"):
        free.check_motion(np.zeros((2, 3)))
