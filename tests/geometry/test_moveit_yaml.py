"""MoveIt YAML within bounds (issue 33 items 1-3): aliases, deep nesting, huge files and long quotes refused fast."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from drd_planner.exceptions import GeometryError
from drd_planner.geometry.moveit_request import parse_motion_plan_request
from drd_planner.geometry.moveit_scene import parse_planning_scene, read_planning_scene
from drd_planner.geometry.moveit_yaml import MAX_YAML_DEPTH, load_yaml, quoted, read_yaml_text


def _alias_bomb(levels: int = 9) -> str:
    """A few hundred bytes whose aliases expand to 9**levels values."""
    lines = ['a0: &a0 ["xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx"]']
    for k in range(1, levels + 1):
        previous = ", ".join([f"*a{k - 1}"] * 9)
        lines.append(f"a{k}: &a{k} [{previous}]")
    return "\n".join(lines) + f"\nworld: {{collision_objects: [{{id: *a{levels}, primitives: []}}]}}\n"


def test_an_alias_bomb_is_refused_at_once_with_a_short_message() -> None:
    text = _alias_bomb()
    assert len(text) < 700
    t0 = time.perf_counter()
    with pytest.raises(GeometryError, match="aliases") as info:
        parse_planning_scene(text, source="bomb.yaml")
    assert time.perf_counter() - t0 < 1.0
    assert len(str(info.value)) < 500
    with pytest.raises(GeometryError, match="aliases"):
        parse_motion_plan_request(text, source="bomb.yaml")


def test_deep_nesting_is_refused_without_a_recursion_error() -> None:
    deep = "world: " + "[" * 100_000 + "]" * 100_000
    with pytest.raises(GeometryError, match=f"nested deeper than {MAX_YAML_DEPTH} levels"):
        parse_planning_scene(deep, source="deep.yaml")
    assert load_yaml("a: [[[1]]]", source="x") == {"a": [[[1]]]}  # ordinary nesting is fine


def test_files_are_sized_before_they_are_read(tmp_path: Path) -> None:
    sparse = tmp_path / "huge.yaml"
    with sparse.open("wb") as handle:
        handle.truncate(3 << 30)  # 3 GiB, no disk used
    link = tmp_path / "scene0001.yaml"
    os.symlink(sparse, link)
    t0 = time.perf_counter()
    with pytest.raises(GeometryError, match=r"has 3221225472 bytes; at most \d+ are read"):
        read_planning_scene(link)
    assert time.perf_counter() - t0 < 1.0
    with pytest.raises(GeometryError, match="not a regular file"):
        read_yaml_text(tmp_path, "planning scene")
    small = tmp_path / "small.yaml"
    small.write_text("world: {collision_objects: []}\n")
    assert read_yaml_text(small, "planning scene", max_bytes=100).startswith("world")
    with pytest.raises(GeometryError, match="has 31 bytes; at most 10"):
        read_yaml_text(small, "planning scene", max_bytes=10)


def test_offending_values_are_quoted_short() -> None:
    huge = "x" * 1_000_000
    assert len(quoted(huge)) < 80
    assert len(quoted(list(range(10**5)))) < 80
    scene = f"world: {{collision_objects: [{{id: box, operation: '{huge}', primitives: []}}]}}\n"
    with pytest.raises(GeometryError, match="operation") as info:
        parse_planning_scene(scene, source="long.yaml")
    assert len(str(info.value)) < 300
