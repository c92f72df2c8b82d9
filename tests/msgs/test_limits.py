"""Message size limits: defaults, refusal texts that name the parameter, coordinate checks."""

from __future__ import annotations

import numpy as np

from drd_msgs_py.limits import DEFAULT_LIMITS, MessageLimits, limit_refusal


def test_refusals_name_the_limit_its_value_and_the_parameter() -> None:
    limits = MessageLimits(max_markers=3)
    assert (
        limits.refusal("max_markers", "4 markers")
        == "4 markers, over the limit max_markers = 3 (parameter max_markers)"
    )
    assert limit_refusal("min_terrain_cell_size", 0.05, "cells are 0.01 m", side="under").startswith(
        "cells are 0.01 m, under the limit min_terrain_cell_size = 0.05"
    )
    assert DEFAULT_LIMITS == MessageLimits()
    assert DEFAULT_LIMITS.max_terrain_cells == 250_000


def test_coordinates_beyond_the_limit_are_named_and_nan_is_skipped() -> None:
    limits = MessageLimits(max_coordinate=10.0)
    assert limits.coordinate_problem(np.array([1.0, np.nan, -9.0]), "z") is None
    assert limits.coordinate_problem(np.array([]), "z") is None
    assert limits.coordinate_problem(np.full(3, np.nan), "z") is None
    problem = limits.coordinate_problem(np.array([[1.0, -12.5]]), "terrain cloud x values")
    assert problem is not None
    assert "x values reach 12.5 m" in problem
    assert "max_coordinate = 10.0" in problem
