"""The authors' synthetic Bernoulli test sets (``dataset_bern_test_*/test_setN.mat``).

Each set has ``region_test`` (regions x tests, 0/1), ``test_bias`` (1 x tests, theta),
``test_cost`` (1 x tests) and ``test_outcome_set`` (problems x tests, 1 = free). Regions play the
role of library paths and tests the role of edges.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from drd_planner.core.library import PathLibrary
from drd_planner.data.matfile import load_mat_variable
from drd_planner.exceptions import DatasetError


@dataclass(frozen=True)
class BernoulliTestSet:
    """A synthetic benchmark: library (regions), bias, costs and the outcome of every problem.

    Attributes:
        library: m regions over T tests.
        theta: (T,) float64 bias P(test passes).
        costs: (T,) float64 test costs.
        outcomes: (k, T) bool, one row per problem.
    """

    library: PathLibrary
    theta: npt.NDArray[np.float64]
    costs: npt.NDArray[np.float64]
    outcomes: npt.NDArray[np.bool_]


def load_bernoulli_test_set(path: str | Path) -> BernoulliTestSet:
    """Load ``test_setN.mat``; a missing or malformed file raises DatasetError naming it."""
    p = Path(path)
    regions = load_mat_variable(p, "region_test").astype(bool)
    theta = load_mat_variable(p, "test_bias").astype(np.float64).ravel()
    costs = load_mat_variable(p, "test_cost").astype(np.float64).ravel()
    outcomes = load_mat_variable(p, "test_outcome_set").astype(bool)
    num_tests = regions.shape[1]
    if theta.shape != (num_tests,) or costs.shape != (num_tests,) or outcomes.shape[1:] != (num_tests,):
        raise DatasetError(f"{p}: region_test, test_bias, test_cost and test_outcome_set disagree in size")
    paths = tuple(np.flatnonzero(row).astype(np.int64) for row in regions)
    return BernoulliTestSet(PathLibrary(paths, num_tests), theta, costs, outcomes)


def load_stored_costs(path: str | Path) -> npt.NDArray[np.int64]:
    """The authors' stored per-problem costs (policies x problems) from a results ``.mat`` file."""
    return load_mat_variable(Path(path), "cumulative_cost_set").astype(np.int64)
