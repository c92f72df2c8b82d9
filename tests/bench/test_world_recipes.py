"""World recipes: JSON round trip, the same world in any process, scene folders, clear refusals."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import pytest
from conftest import SHARED_DATA

from drd_planner.bench.world_recipes import WorldRecipe, scene_recipes, seeded_recipes
from drd_planner.domains.arm import ArmDomain
from drd_planner.exceptions import ProblemError

SCENE = """world:
  collision_objects:
    - id: cube
      primitives: [{type: box, dimensions: [0.1, 0.2, 0.3]}]
      primitive_poses: [{position: [0.5, 0.0, 0.4], orientation: [0, 0, 0, 1]}]
"""


def test_recipes_round_trip_and_remake_the_same_world(small_arm: ArmDomain, tmp_path: Path) -> None:
    seeded = seeded_recipes("clutter", [3, 4])
    assert [r.label for r in seeded] == ["clutter:3", "clutter:4"]
    assert {r.family for r in seeded} == {"clutter"}
    for recipe in seeded:
        assert WorldRecipe.from_json(recipe.to_json()) == recipe
    assert seeded[0].make(small_arm) == small_arm.make_world("clutter", 3)
    (tmp_path / "scene0002.yaml").write_text(SCENE)
    (tmp_path / "scene0001.yaml").write_text(SCENE.replace("cube", "brick"))
    (tmp_path / "request0001.yaml").write_text("not a scene")
    scenes = scene_recipes(tmp_path)
    assert [r.label for r in scenes] == [f"{tmp_path.name}/scene0001", f"{tmp_path.name}/scene0002"]
    assert [r.label for r in scene_recipes(tmp_path, limit=1)] == [f"{tmp_path.name}/scene0001"]
    world = WorldRecipe.from_json(scenes[0].to_json()).make(small_arm)
    assert [o.name for o in world.obstacles] == ["brick"]


def test_mbm_folders_give_one_recipe_per_scene(small_arm: ArmDomain) -> None:
    folder = SHARED_DATA / "mbm" / "box_panda"
    if not folder.is_dir():
        pytest.skip(f"{folder} not present (set DRD_SHARED_DATA)")
    recipes = scene_recipes(folder, limit=2)
    assert [r.family for r in recipes] == ["box_panda", "box_panda"]
    assert len(recipes[0].make(small_arm).obstacles) > 3


def test_bad_recipes_are_refused(tmp_path: Path) -> None:
    with pytest.raises(ProblemError, match=r"no scene\*\.yaml files"):
        scene_recipes(tmp_path)
    with pytest.raises(ProblemError, match="needs a model and a seed, or a scene"):
        WorldRecipe("bare", "x").make(SimpleNamespace(name="d"))
    with pytest.raises(ProblemError, match="cannot read scene files"):
        WorldRecipe("s", "x", scene="a.yaml").make(SimpleNamespace(name="planar"))
    with pytest.raises(ProblemError, match="bad world recipe"):
        WorldRecipe.from_json({"label": "no family"})
