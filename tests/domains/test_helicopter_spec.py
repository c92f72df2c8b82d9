"""HelicopterParams: the helicopter spec with its validation; stored specs load unchanged."""

from __future__ import annotations

import json

import pytest

from drd_planner.domains.helicopter_spec import HelicopterParams
from drd_planner.exceptions import ProblemError


def test_default_spec_round_trips_through_json() -> None:
    spec = HelicopterParams().to_spec()
    assert set(spec) == {
        "lattice",
        "vehicle_radius",
        "margin",
        "terrain_cell",
        "world_margin",
        "wire_segments",
        "models",
    }
    assert set(spec["models"]) == {"wires", "canyon", "terrain", "corridors"}
    again = HelicopterParams.from_spec(json.loads(json.dumps(spec)))
    assert again.to_spec() == spec


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ({"robot": 1}, "unknown helicopter spec keys: robot; valid keys: lattice,"),
        ({"vehicle_radius": 0}, "'vehicle_radius' must be finite and > 0"),
        ({"margin": "x"}, "'margin' must be a number"),
        ({"vehicle_radius": 2.0}, "exceeds the vehicle radius"),
        ({"wire_segments": True}, "wire_segments"),
        ({"models": []}, "'models' must be a dict"),
        ({"models": {"ocean": {}}}, "unknown helicopter world models"),
    ],
)
def test_bad_specs(spec: dict[str, object], message: str) -> None:
    with pytest.raises(ProblemError, match=message):
        HelicopterParams.from_spec(spec)


def test_model_lookup() -> None:
    params = HelicopterParams()
    assert params.model("wires") is params.models["wires"]
    with pytest.raises(ProblemError, match="unknown helicopter world model 'ocean'"):
        params.model("ocean")
