"""Tests of the world models' common frame and draw helpers."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.domains.helicopter_world_frame import WorldFrame, draw_integer, draw_uniform, smoothstep

FRAME = WorldFrame((0.0, 100.0), (-50.0, 50.0), 20.0, 10.0, ((0.0, 0.0, 60.0),), 5.0, 40.0)


def test_grid_and_heightfield_cover_the_corridor_plus_margin() -> None:
    xs, ys = FRAME.grid()
    assert xs[0] == -20.0
    assert xs[-1] == pytest.approx(120.0)
    assert ys[0] == -70.0
    assert ys[-1] == pytest.approx(70.0)
    field = FRAME.heightfield(np.zeros((ys.size, xs.size)))
    assert tuple(field.origin) == (-20.0, -70.0)
    assert field.cell_size == 10.0


def test_draw_helpers() -> None:
    rng = np.random.default_rng(0)
    assert draw_uniform(rng, (3.0, 3.0)) == 3.0  # an empty range draws nothing
    state = rng.bit_generator.state
    assert draw_uniform(rng, (1.0, 2.0)) == float(np.random.default_rng(0).uniform(1.0, 2.0))
    assert rng.bit_generator.state != state
    assert {draw_integer(rng, (1, 3)) for _ in range(200)} == {1, 2, 3}
    assert np.allclose(smoothstep(np.array([-1.0, 0.0, 0.5, 1.0, 2.0])), [0.0, 0.0, 0.5, 1.0, 1.0])
