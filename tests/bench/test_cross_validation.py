"""Cross-validation: every feasible world is tested once, by a fold that never trained on it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from drd_planner.bench.cross_validation import FoldSettings, cross_validate
from drd_planner.bench.runner import PolicySettings, run_world, train_bias
from drd_planner.core.problem import Problem
from drd_planner.core.tree import build_tree
from drd_planner.data.planar_problem import make_planar_problem
from drd_planner.exceptions import DrdError


@pytest.fixture(scope="module")
def problem() -> Problem:
    return make_planar_problem(num_vertices=60, model="one_wall", num_worlds=90, max_paths=40, seed=4)


def test_every_feasible_world_is_tested_once_by_a_fold_that_held_it_out(problem: Problem) -> None:
    result = cross_validate(
        problem,
        policies=("bisect", "direct_bisect"),
        folds=3,
        seed=2,
        settings=FoldSettings(eta=0.2, region_rules=("probability",)),
    )
    worlds = problem.require_worlds()
    feasible = np.flatnonzero(worlds.R.any(axis=1))
    assert np.array_equal(np.sort(result.worlds), feasible)
    assert set(result.fold_of.tolist()) == {0, 1, 2}
    assert result.etas == (0.2, 0.2, 0.2)
    # Re-run one world of fold 1 by hand: tree and bias learnt from every world outside that fold.
    held = np.sort(result.worlds[result.fold_of == 1])
    fit = np.setdiff1d(np.arange(worlds.num_worlds), held)
    sub = dataclasses.replace(problem, worlds=worlds.subset(fit, held))
    tree = build_tree(sub, progress=False)
    position = 3
    world = int(held[position])
    for name in ("bisect", "direct_bisect"):
        episode = run_world(
            sub,
            name,
            world,
            theta=train_bias(sub),
            tree=tree,
            seed=2 + position,
            settings=PolicySettings(eta=0.2),
        )
        assert result.checks[name][result.worlds == world][0] == episode.num_checks
    assert (result.lower_bound <= result.checks["bisect"] + 1e-9).all()


def test_summary_pairs_policies_and_is_deterministic(problem: Problem) -> None:
    a = cross_validate(problem, policies=("bisect", "direct_bisect"), folds=3, seed=1)
    b = cross_validate(problem, policies=("bisect", "direct_bisect"), folds=3, seed=1)
    assert a.as_json("bisect") == b.as_json("bisect")
    summary = a.as_json("bisect")
    diff = summary["policies"]["direct_bisect"]["minus_bisect"]
    expected = float(np.mean(a.checks["direct_bisect"] - a.checks["bisect"]))
    assert diff["mean"] == pytest.approx(expected)
    assert diff["ci95"][0] <= expected <= diff["ci95"][1]
    assert all(0.0 < eta <= 1.0 for eta in a.etas)  # validated per fold
    assert len(a.settings["chosen_region_rules"]) == 3  # so is the region rule, by default
    assert set(a.settings["chosen_region_rules"]) <= {"probability", "per_check"}
    given = cross_validate(
        problem,
        policies=("direct_bisect",),
        folds=3,
        seed=1,
        settings=FoldSettings(eta=0.2, pseudo_counts=(None,), region_rules=("per_check",)),
    )
    assert given.settings["chosen_region_rules"] == ["per_check"] * 3


def test_bad_fold_counts_are_refused(problem: Problem) -> None:
    with pytest.raises(DrdError, match="at least 2 folds"):
        cross_validate(problem, policies=("bisect",), folds=1)
    with pytest.raises(DrdError, match="cannot fill"):
        cross_validate(problem, policies=("bisect",), folds=10_000)
