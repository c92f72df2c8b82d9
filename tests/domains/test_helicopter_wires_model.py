"""Tests of the wires world model drawn directly (the full worlds are tested in test_helicopter_worlds)."""

from __future__ import annotations

import numpy as np

from drd_planner.domains.helicopter_wires_model import draw_wires
from drd_planner.domains.helicopter_world_frame import WorldFrame
from drd_planner.domains.helicopter_world_params import WiresParams

FRAME = WorldFrame((0.0, 700.0), (-250.0, 250.0), 100.0, 25.0, ((0.0, 0.0, 65.0),), 6.0, 40.0)


def test_lines_have_towers_and_conductors_between_them() -> None:
    params = WiresParams(lines=(2, 2), conductors=(2, 2))
    draw = draw_wires(np.random.default_rng(1), params, FRAME)
    assert len(draw.info["lines"]) == 2
    towers = [name for name, _, _ in draw.solids]
    assert all(name.startswith("tower_") for name in towers)
    per_line = [sum(name.startswith(f"tower_{i}_") for name in towers) for i in range(2)]
    assert len(draw.wires) == sum(2 * (k - 1) for k in per_line)
    again = draw_wires(np.random.default_rng(1), params, FRAME)
    assert again.wires == draw.wires
    assert np.array_equal(again.terrain.heights, draw.terrain.heights)
