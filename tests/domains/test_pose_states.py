"""Tests for drd_planner.domains.pose_states: (x, y, z, heading) states of a position and a yaw."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drd_planner.domains.pose_states import state_from_pose, wrap_angle, yaw_from_quaternion
from drd_planner.exceptions import PlanningError


@pytest.mark.parametrize(
    ("angle", "wrapped"),
    [
        (0.0, 0.0),
        (math.pi, -math.pi),
        (-math.pi, -math.pi),
        (3 * math.pi / 2, -math.pi / 2),
        (-7.0, -7.0 + 2 * math.pi),
    ],
)
def test_wrap_angle_lands_in_minus_pi_to_pi(angle: float, wrapped: float) -> None:
    assert wrap_angle(angle) == pytest.approx(wrapped)
    assert -math.pi <= wrap_angle(angle) < math.pi


def test_state_from_pose_wraps_the_heading_and_refuses_bad_input() -> None:
    np.testing.assert_allclose(state_from_pose([1.0, 2.0, 3.0], 5 * math.pi / 2), [1.0, 2.0, 3.0, math.pi / 2])
    with pytest.raises(PlanningError, match="three finite numbers"):
        state_from_pose([1.0, math.nan, 0.0], 0.0)
    with pytest.raises(PlanningError, match="finite angle"):
        state_from_pose([1.0, 2.0, 3.0], math.inf)


def test_yaw_from_a_quaternion_about_z_and_refusals() -> None:
    for yaw in (-3.0, -1.0, 0.0, 0.5, 3.0):
        q = [0.0, 0.0, np.sin(yaw / 2), np.cos(yaw / 2)]
        assert yaw_from_quaternion(q) == pytest.approx(yaw)
        assert yaw_from_quaternion(2.5 * np.asarray(q)) == pytest.approx(yaw)  # need not be normalised
    for bad in ([0.0, 0.0, 0.0, 0.0], [0.0, 0.0, np.nan, 1.0], [1.0, 2.0, 3.0]):
        with pytest.raises(PlanningError, match="quaternion"):
            yaw_from_quaternion(bad)
