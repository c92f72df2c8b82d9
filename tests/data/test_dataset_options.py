"""Tests of the dataset build settings: the recipe (contents) and the options (computation)."""

from __future__ import annotations

import shlex

import numpy as np
import pytest

from drd_planner.data.dataset_options import BuildOptions, DatasetRecipe
from drd_planner.exceptions import DatasetError


def test_recipe_normalises_its_numbers() -> None:
    recipe = DatasetRecipe("planar", "forest", np.int64(10), np.int64(3), test_fraction=1)
    assert type(recipe.num_worlds) is int
    assert type(recipe.seed) is int
    assert type(recipe.test_fraction) is float
    assert recipe.test_fraction == 1.0


def test_recipe_command_lists_only_content_settings() -> None:
    recipe = DatasetRecipe(
        "helicopter", "terrain", 12, 1, domain_spec={"models": {"terrain": {"mirror": 0}}}, k=3, max_paths=40
    )
    argv = shlex.split(recipe.command())
    assert argv[:6] == ["drd", "build-dataset", "--domain", "helicopter", "--world-model", "terrain"]
    assert argv[argv.index("--k") + 1] == "3"
    assert argv[argv.index("--max-paths") + 1] == "40"
    assert argv[argv.index("--domain-spec") + 1] == '{"models": {"terrain": {"mirror": 0}}}'
    assert "--k" not in DatasetRecipe("planar", "forest", 5, 0).command()
    # Leaving the edge trajectories out changes the file, so the command says so.
    assert "--no-trajectories" not in argv
    lean = DatasetRecipe("planar", "forest", 5, 0, include_trajectories=False)
    assert shlex.split(lean.command())[-1] == "--no-trajectories"


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"num_worlds": 0}, "num_worlds must be a positive integer"),
        ({"num_worlds": True}, "num_worlds must be a positive integer"),
        ({"k": 0}, "k must be a positive integer"),
        ({"max_paths": 2.5}, "max_paths must be a positive integer"),
        ({"seed": -1}, "seed must be a non-negative integer"),
        ({"test_fraction": -0.1}, r"test fraction must lie in \[0, 1\]"),
    ],
)
def test_bad_recipes_are_refused(kwargs: dict[str, object], message: str) -> None:
    settings: dict[str, object] = {"domain": "planar", "world_model": "forest", "num_worlds": 4, "seed": 0}
    with pytest.raises(DatasetError, match=message):
        DatasetRecipe(**{**settings, **kwargs})  # type: ignore[arg-type]


def test_options() -> None:
    assert not BuildOptions().parallel
    assert BuildOptions(workers=2).parallel
    assert BuildOptions(scheduler="tcp://h:1").parallel
    with pytest.raises(DatasetError, match="chunk_size must be a positive integer"):
        BuildOptions(chunk_size=0)
    with pytest.raises(DatasetError, match="max_chunks must be a positive integer"):
        BuildOptions(max_chunks=0)
    with pytest.raises(DatasetError, match="start method 'teleport' is not available here"):
        BuildOptions(start_method="teleport")
