"""Map limits: defaults, validation naming the field, building from node parameters, refusal texts."""

from __future__ import annotations

import dataclasses
from typing import Any

import pytest

from drd_planner.exceptions import DrdError, ParameterError
from drd_planner.geometry.map_limits import UNKNOWN_TERRAIN_CHOICES, MapLimits


def test_defaults() -> None:
    limits = MapLimits()
    assert limits == MapLimits.DEFAULT
    assert limits.as_parameters() == {
        "max_message_bytes": 32 * 2**20,
        "max_terrain_cells": 250_000,
        "min_terrain_cell_size": 0.05,
        "max_coordinate": 1e6,
        "max_markers": 10_000,
        "max_line_points": 100_000,
        "max_mesh_triangles": 100_000,
        "max_robot_links": 512,
        "max_robot_spheres": 1024,
        "unknown_terrain": "blocked",
    }
    assert UNKNOWN_TERRAIN_CHOICES[0] == "blocked"
    descriptions = MapLimits.descriptions()
    assert set(descriptions) == set(limits.as_parameters())
    assert descriptions["max_terrain_cells"].startswith("grid points:")
    assert descriptions["min_terrain_cell_size"].startswith("metres:")


@pytest.mark.parametrize(
    ("values", "words"),
    [
        ({"max_markers": 0}, "map limit max_markers: must be an integer > 0, got 0"),
        ({"max_terrain_cells": -5}, "map limit max_terrain_cells: must be an integer > 0"),
        ({"max_robot_links": 2.5}, "map limit max_robot_links: must be an integer > 0, got 2.5"),
        ({"max_robot_spheres": True}, "map limit max_robot_spheres: must be an integer > 0, got True"),
        ({"max_coordinate": float("inf")}, "map limit max_coordinate: must be finite and > 0, got inf"),
        ({"min_terrain_cell_size": 0.0}, "map limit min_terrain_cell_size: must be finite and > 0"),
        ({"min_terrain_cell_size": "1"}, "map limit min_terrain_cell_size: must be a number > 0"),
        ({"unknown_terrain": "free"}, "must be one of 'blocked', 'highest_neighbour', got 'free'"),
    ],
)
def test_bad_values_are_refused_naming_the_field(values: dict[str, Any], words: str) -> None:
    with pytest.raises(ParameterError) as info:
        MapLimits.from_parameters(values)
    assert words in str(info.value)
    assert isinstance(info.value, DrdError)
    with pytest.raises(ParameterError):
        MapLimits(**values)
    (name,) = values
    assert MapLimits.check_value(name, values[name]) is not None
    assert MapLimits.check_value(name, getattr(MapLimits.DEFAULT, name)) is None


def test_from_parameters_takes_its_fields_and_ignores_other_parameters() -> None:
    limits = MapLimits.from_parameters(
        {"max_terrain_cells": 4e6, "max_coordinate": 5000, "unknown_terrain": "highest_neighbour", "seed": 7}
    )
    assert limits.max_terrain_cells == 4_000_000
    assert isinstance(limits.max_terrain_cells, int)
    assert limits.max_coordinate == 5000.0
    assert isinstance(limits.max_coordinate, float)
    assert limits.unknown == "highest_neighbour"
    assert dataclasses.replace(limits, max_markers=3).max_markers == 3
    with pytest.raises(ParameterError, match="'seeds' is not a map limit"):
        MapLimits.check_value("seeds", 1)


def test_refusal_and_coordinate_texts_name_the_parameter() -> None:
    limits = MapLimits(max_terrain_cells=4_000_000)
    assert limits.refusal("max_terrain_cells", "terrain cloud has 16000000 cells") == (
        "terrain cloud has 16000000 cells, over the limit max_terrain_cells = 4000000 (parameter max_terrain_cells)"
    )
    assert limits.coordinate_problem([1.0, float("nan"), -2.0], "z") is None
    assert limits.coordinate_problem([], "z") is None
    assert limits.coordinate_problem([float("nan")], "z") is None
    assert limits.coordinate_problem([3.0, -2e6], "terrain z") == (
        "terrain z reach 2e+06 m in absolute value, over the limit max_coordinate = 1000000.0 "
        "(parameter max_coordinate)"
    )
    assert "reach inf m" in str(limits.coordinate_problem([float("-inf")], "x"))
