"""``drd plan`` on a dataset world as a library call: the check log and outcome printed, and the refusals."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from drd_planner.core.episode import TableOracle
from drd_planner.data.problem_source import ProblemSource
from drd_planner.exceptions import DrdError
from drd_planner.planner import Planner, load_prior
from drd_planner.planner.dataset_plan import DatasetPlanOptions, plan_dataset_world, print_plan

HELI_WIRES = Path(__file__).resolve().parents[2] / "trees" / "heli_wires.npz"


def test_the_world_must_be_chosen() -> None:
    options = DatasetPlanOptions(prior=str(HELI_WIRES), source=ProblemSource())
    with pytest.raises(DrdError, match="--world is required"):
        plan_dataset_world(options)


def test_a_plan_prints_one_line_per_check_and_its_outcome(capsys: pytest.CaptureFixture[str]) -> None:
    prior = load_prior(HELI_WIRES)
    planner = Planner(prior)
    tree = prior.trees[0]
    free = TableOracle(np.ones(prior.graph.num_edges, dtype=bool))
    result = planner.plan(tree.start, tree.goal, free, seed=0)
    print_plan(planner, result)
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == result.num_checks + 1
    assert all("free" in line for line in lines[:-1])  # every edge is free in this world
    assert lines[-1].startswith("  -> found: ")
    assert f"query tree:{tree.name}" in lines[-1]
