"""The RRT-Connect worker's answers: one-state checks for states, dense straight motions for motions."""

from __future__ import annotations

import numpy as np

from drd_planner.bench.rrt_connect_worker import _Counter
from drd_planner.domains.arm import ArmDomain
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Box, Pose


def test_states_and_motions_are_answered_by_the_checker_and_counted(small_arm: ArmDomain) -> None:
    start = np.asarray(small_arm.params.start, dtype=np.float64)
    goal = np.asarray(small_arm.params.goal, dtype=np.float64)
    scene = Scene(margin=0.0)
    scene.add(Box([0.15, 0.15, 0.15]), Pose(small_arm.end_effector_positions(goal[None])[0].tolist()), name="can")
    checker = small_arm.scene_checker(scene)
    counter = _Counter(checker, small_arm.resolution, 7)
    assert counter.state_valid(start.tolist())
    assert not counter.state_valid(goal.tolist())
    assert not counter.motion_valid(start.tolist(), goal.tolist())
    nearby = start + 0.02
    assert counter.motion_valid(start.tolist(), nearby.tolist())
    assert (counter.states, counter.motions) == (2, 2)
    np.testing.assert_array_equal(counter.vector(goal.tolist()), goal)
