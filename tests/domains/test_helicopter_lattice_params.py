"""Tests of the helicopter lattice parameters: defaults, normalisation and every validation error."""

from __future__ import annotations

import pytest

from drd_planner.domains.helicopter_lattice_params import LatticeParams
from drd_planner.exceptions import ProblemError


def test_defaults_and_normalisation() -> None:
    p = LatticeParams(x_range=[0, 700], z_levels=[40, 65, 90], start_level=0, axis_primitives=[[1, 0, 0]])
    assert p.x_range == (0.0, 700.0)
    assert p.z_levels == (40.0, 65.0, 90.0)
    assert p.axis_primitives == ((1, 0, 0),)
    assert p.level_index(p.start_level) == 0
    assert p.level_index(p.goal_level) == 1
    assert LatticeParams.from_dict(p.to_dict()) == p


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"x_range": (1.0,)}, "pair of numbers"),
        ({"start": (0.0, float("inf"))}, "finite"),
        ({"y_range": (5.0, 5.0)}, "min < max"),
        ({"turning_radius": "far"}, "must be a number"),
        ({"sample_spacing": 0.0}, "positive and finite"),
        ({"z_levels": ["a"]}, "list of numbers"),
        ({"z_levels": (50.0, 40.0)}, "strictly increasing"),
        ({"climb": "up"}, "climb must be one of"),
        ({"goal_level": 3}, "goal_level"),
        ({"start_level": True}, "start_level"),
        ({"axis_primitives": [[1, 0]]}, "integer triples"),
        ({"axis_primitives": [[0, 0, 1]]}, "must move"),
        ({"diagonal_primitives": [[1, 1, 0], [1, 1, 0]]}, "duplicate"),
    ],
)
def test_validation_errors(fields: dict, message: str) -> None:
    with pytest.raises(ProblemError, match=message):
        LatticeParams(**fields)
