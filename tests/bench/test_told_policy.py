"""direct_bisect told a group of worlds (drd_planner.bench.told_policy): an upper bound on the group's optimum."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import gccd_folder
from optima_cases import TOL

from drd_planner.bench.known_worlds import known_worlds_optimum
from drd_planner.bench.runner import PolicySettings
from drd_planner.bench.told_policy import TOLD_SETTINGS, told_checks
from drd_planner.core.problem import Problem
from drd_planner.data.gccd import load_gccd_folder
from drd_planner.exceptions import ProblemError


@pytest.fixture(scope="module")
def problem() -> Problem:
    return load_gccd_folder(gccd_folder("dataset_2d_1"))


def _group(problem: Problem, size: int) -> np.ndarray:
    """The first ``size`` test worlds that have a valid library path."""
    worlds = problem.require_worlds()
    test = np.asarray(worlds.test_ids)
    return test[problem.library.valid_paths(worlds.X[test]).any(axis=1)][:size]


@pytest.mark.parametrize("rule", ["probability", "per_check"])
def test_told_checks_are_never_below_the_groups_exact_optimum(problem: Problem, rule: str) -> None:
    group = _group(problem, 7)
    checks = told_checks(problem, group, rule)
    assert checks.shape == (len(TOLD_SETTINGS), group.size)
    optimum = known_worlds_optimum(problem.require_worlds().X[group], problem.library, problem.edge_costs)
    # Any policy told the group is a policy for it: no setting's mean may go below the optimum.
    assert np.all(checks.mean(axis=1) >= optimum - TOL)
    # The tree grown to single worlds (eta 1e-4) uses what it was told: it beats BiSECt from the root.
    follow, root = checks[0].mean(), checks[TOLD_SETTINGS.index(PolicySettings(eta=1.0))].mean()
    assert follow <= root
    assert np.array_equal(checks, told_checks(problem, group, rule))  # seeded: the same checks again


def test_told_one_world_proves_one_of_its_valid_paths(problem: Problem) -> None:
    (world,) = _group(problem, 1)
    x = problem.require_worlds().X[world]
    checks = told_checks(problem, [world], "probability", settings=(PolicySettings(eta=1e-4),))
    oracle = problem.library.path_costs(problem.edge_costs)[problem.library.valid_paths(x[None, :])[0]].min()
    assert checks.shape == (1, 1)
    assert checks[0, 0] >= oracle - TOL


def test_bad_rule_or_group_is_refused(problem: Problem) -> None:
    with pytest.raises(ProblemError, match="probability"):
        told_checks(problem, [0], "shortest")
    with pytest.raises(ProblemError, match="world rows"):
        told_checks(problem, [], "probability")
    with pytest.raises(ProblemError, match="world rows"):
        told_checks(problem, [problem.require_worlds().num_worlds], "probability")
