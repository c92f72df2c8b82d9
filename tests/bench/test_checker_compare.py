"""Sphere and mesh checkers compared edge by edge: outcomes as the checkers give them, misses explained."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import SMALL_ARM_SPEC

from drd_planner.bench.checker_compare import compare_world, summarize
from drd_planner.bench.world_recipes import WorldRecipe, seeded_recipes
from drd_planner.domains.arm import ArmDomain
from drd_planner.domains.base import domain_from_spec
from drd_planner.exceptions import ProblemError

SMALL = SMALL_ARM_SPEC
# A 2 cm cube against the back of the base: inside its collision mesh, 5 cm clear of the base sphere.
REAR = """world:
  collision_objects:
    - id: rear
      primitives: [{type: box, dimensions: [0.02, 0.02, 0.02]}]
      primitive_poses: [{position: [-0.14, -0.04, 0.03], orientation: [0, 0, 0, 1]}]
"""


@pytest.fixture(scope="module")
def meshes(small_arm_meshes: ArmDomain) -> ArmDomain:
    return small_arm_meshes


def test_outcomes_are_the_checkers_own(small_arm: ArmDomain, meshes: ArmDomain) -> None:
    recipe = seeded_recipes("clutter", [4])[0]
    edges = np.arange(30)
    result = compare_world(small_arm, meshes, recipe, edges)
    world = recipe.make(small_arm)
    np.testing.assert_array_equal(result.free_spheres, small_arm.checker(world).check_many(edges))
    np.testing.assert_array_equal(result.free_meshes, meshes.checker(world).check_many(edges))
    assert result.ms_spheres.shape == result.ms_meshes.shape == (30,)
    assert np.all(result.ms_meshes > 0)
    assert len(result.misses) == result.meshes_only_blocked
    for miss in result.misses:
        assert miss.link.startswith("panda_")
        assert miss.depth_m >= 0
        assert miss.sample >= 0
        assert miss.obstacle
    block = summarize([result])["all"]
    assert block["agree"] + block["spheres_only_blocked"] + block["meshes_only_blocked"] == 30
    assert block["time_ratio"] == pytest.approx(block["ms_meshes_mean"] / block["ms_spheres_mean"])


def test_a_box_the_spheres_miss_is_reported_with_where(small_arm: ArmDomain, meshes: ArmDomain, tmp_path: Path) -> None:
    (tmp_path / "scene0001.yaml").write_text(REAR)
    recipe = WorldRecipe("rear", "rear", scene=str(tmp_path / "scene0001.yaml"))
    result = compare_world(small_arm, meshes, recipe, np.arange(5))
    assert result.free_spheres.all()
    assert not result.free_meshes.any()
    assert len(result.misses) == 5
    for miss in result.misses:
        assert (miss.sample, miss.link, miss.obstacle, miss.reason) == (-1, "panda_link0", "rear", "contact")
        assert 0.0 < miss.depth_m < 0.03
        assert miss.sphere_clearance_m > 0.04
    summary = summarize([result])
    assert summary["families"]["rear"]["meshes_only_blocked"] == 5
    assert summary["misses_by_link"]["panda_link0"]["edges"] == 5
    assert summary["misses_by_link"]["panda_link0"]["sphere_clearance_mm_median"] > 40


def test_the_two_domains_must_share_a_roadmap_and_differ_in_model(small_arm: ArmDomain, meshes: ArmDomain) -> None:
    recipe = seeded_recipes("clutter", [4])[0]
    with pytest.raises(ProblemError, match="collision_model 'meshes'"):
        compare_world(small_arm, small_arm, recipe, np.arange(2))
    other = domain_from_spec("arm", {**SMALL, "seed": 4, "collision_model": "meshes"})
    assert isinstance(other, ArmDomain)
    with pytest.raises(ProblemError, match="share one roadmap"):
        compare_world(small_arm, other, recipe, np.arange(2))
