"""Tests of the canyon world model drawn directly (the full worlds are tested in test_helicopter_worlds)."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.domains.helicopter_canyon_model import draw_canyon
from drd_planner.domains.helicopter_world_frame import WorldFrame
from drd_planner.domains.helicopter_world_params import CanyonParams

FRAME = WorldFrame((0.0, 700.0), (-250.0, 250.0), 100.0, 25.0, ((0.0, 0.0, 65.0),), 6.0, 40.0)


def test_valley_floor_holds_start_and_goal_and_wires_span_the_rims() -> None:
    params = CanyonParams(spurs=(0, 0), rim_wires=(2, 2))
    draw = draw_canyon(np.random.default_rng(4), params, FRAME)
    floor, wall = draw.info["floor"], draw.info["wall"]
    at_ends = draw.terrain.height_at(np.array([[0.0, 0.0], [700.0, 0.0]]))
    assert at_ends == pytest.approx([floor, floor])
    assert draw.terrain.heights.max() == pytest.approx(wall, abs=1e-6)
    assert len(draw.wires) == 2
    assert draw.solids == ()
