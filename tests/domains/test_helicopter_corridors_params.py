"""Tests of the corridors model's parameter records: defaults, dict round trip and refusals."""

from __future__ import annotations

import json

import pytest

from drd_planner.domains.helicopter_corridors_params import CorridorsParams, KnownLine, KnownZone
from drd_planner.domains.helicopter_params import params_to_dict
from drd_planner.domains.helicopter_world_params import NoFlyZone
from drd_planner.domains.helicopter_worlds import model_params_from_dict
from drd_planner.exceptions import ProblemError


def test_defaults_round_trip_through_json() -> None:
    params = CorridorsParams()
    assert params.lines
    assert params.zones
    text = json.dumps(params_to_dict(params))
    again = model_params_from_dict("corridors", json.loads(text))
    assert again == params
    assert isinstance(again, CorridorsParams)
    assert all(isinstance(line, KnownLine) for line in again.lines)
    assert all(isinstance(zone, KnownZone) for zone in again.zones)


def test_partial_dicts_fill_in_defaults() -> None:
    params = model_params_from_dict(
        "corridors",
        {"lines": [{"name": "a", "route": [[0, 1], [2, 3]]}], "zones": [], "shift_sigma": 0},
    )
    assert isinstance(params, CorridorsParams)
    assert params.lines == (KnownLine(name="a", route=((0.0, 1.0), (2.0, 3.0))),)
    assert params.lines[0].probability == KnownLine().probability
    assert params.zones == ()
    assert params.shift_sigma == 0.0


def test_known_zone_is_a_no_fly_zone_with_a_probability() -> None:
    zone = KnownZone(name="z", shape="prism", center=(5.0, 6.0), size=(10.0, 20.0), yaw_deg=30.0, probability=1)
    column = zone.column()
    assert type(column) is NoFlyZone
    assert (column.shape, column.center, column.size, column.yaw_deg) == (
        "prism",
        (5.0, 6.0),
        (10.0, 20.0),
        30.0,
    )
    assert zone.probability == 1.0
    assert zone.footprint_radius == column.footprint_radius


@pytest.mark.parametrize(
    ("values", "match"),
    [
        ({"grid_units": "feet"}, "grid_units"),
        ({"site_origin": [1.0]}, "site_origin"),
        ({"shift_sigma": -1}, "shift_sigma"),
        ({"tower_radius": 0}, "tower_radius"),
        ({"lines": [{"name": "a", "route": [[0, 0]]}]}, "route"),
        ({"lines": [{"name": "a", "probability": 1.5}]}, "probability"),
        ({"lines": [{"name": "a", "span": [0.5, 2]}]}, "span"),
        ({"lines": [{"name": "a"}, {"name": "a"}]}, "unique"),
        ({"lines": [{"colour": "red"}]}, "unknown"),
        ({"zones": [{"name": "z", "probability": -0.1}]}, "probability"),
        ({"zones": [{"name": "", "radius": 5}]}, "name"),
        ({"zones": "none"}, "list"),
        ({"datum": "high"}, "datum"),
        ({"lines": [{"name": "tap", "requires": "trunk"}, {"name": "trunk"}]}, "not a line listed before"),
        ({"lines": [{"name": "a", "requires": "a"}]}, "another line"),
        (
            {"zones": [{"name": "a", "group": "g", "probability": 0.3}, {"name": "b", "group": "g"}]},
            "share one probability",
        ),
    ],
)
def test_invalid_values_are_refused_with_the_parameter_named(values: dict[str, object], match: str) -> None:
    with pytest.raises(ProblemError, match=match):
        model_params_from_dict("corridors", values)
