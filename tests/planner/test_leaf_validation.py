"""eta and kappa validated on random queries over held-out training worlds."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from drd_planner.data.planar_problem import make_planar_problem
from drd_planner.exceptions import ProblemError
from drd_planner.planner.leaf_validation import (
    BISECT_LEAF,
    leaf_from_options,
    significantly_fewer,
    validate_query_leaf,
)


def test_validation_is_seeded_and_uses_training_worlds_only() -> None:
    problem = make_planar_problem(model="forest", num_worlds=150, seed=2)
    worlds = problem.require_worlds()
    kwargs = {"etas": (0.2, 1.0), "pseudo_counts": (None, 20.0), "queries": 4, "seed": 3}
    a = validate_query_leaf(problem, **kwargs)  # type: ignore[arg-type]
    b = validate_query_leaf(problem, **kwargs)  # type: ignore[arg-type]
    assert a == b
    assert set(a.mean_checks) == {(0.2, None), (0.2, 20.0), (1.0, None), (1.0, 20.0)}
    best = min(a.mean_checks.values())
    if (a.eta, a.pseudo_count) != BISECT_LEAF:  # only a significantly better winner replaces BiSECt
        assert a.mean_checks[(a.eta, a.pseudo_count)] == best < a.mean_checks[BISECT_LEAF]
    assert set(a.validation_ids) <= set(worlds.train_ids.tolist())


def test_the_paired_test() -> None:
    base = np.array([10, 12, 9, 15, 11, 10, 13, 12], dtype=float)
    assert significantly_fewer(base - 3, base)
    assert not significantly_fewer(base, base)
    noisy = base + np.array([-6, 5, -6, 6, -5, 4, -6, 3])
    assert noisy.mean() < base.mean()
    assert not significantly_fewer(noisy, base)
    assert not significantly_fewer(base[:1] - 5, base[:1])


def test_given_settings_skip_validation_and_bad_input_is_refused() -> None:
    problem = make_planar_problem(model="one_wall", num_worlds=60, seed=0)
    assert leaf_from_options(problem, eta=0.4, pseudo_counts=(5.0,), seed=0)[:2] == (0.4, 5.0)
    eta, kappa, _, note = leaf_from_options(problem, eta=None, pseudo_counts=(None,), seed=0)
    assert kappa is None
    assert 0 < eta <= 1
    assert "random queries" in note
    with pytest.raises(ProblemError, match="candidate"):
        validate_query_leaf(problem, etas=())


def test_a_tree_whose_query_cannot_be_validated_uses_the_priors_setting() -> None:
    from drd_planner.planner.leaf_validation import tree_leaf_from_options

    problem = make_planar_problem(model="forest", num_worlds=40, seed=3)
    worlds = problem.require_worlds()
    blocked = dataclasses.replace(
        problem, worlds=dataclasses.replace(worlds, R=np.zeros_like(worlds.R))
    )  # no training world has a free library path: nothing to validate on
    leaf, _, note = tree_leaf_from_options(blocked, eta=None, pseudo_counts=(None,), seed=0, tree_options={})
    assert leaf is None
    assert "not validated on this query" in note
    leaf, _, note = tree_leaf_from_options(problem, eta=None, pseudo_counts=(None,), seed=0, tree_options={})
    assert leaf is not None
    assert note.startswith("its own eta")


def test_region_rules_are_validated_on_the_same_episodes() -> None:
    from drd_planner.core.region_rule import REGION_RULES

    problem = make_planar_problem(model="forest", num_worlds=150, seed=2)
    choice = validate_query_leaf(
        problem, etas=(0.2, 1.0), pseudo_counts=(None,), region_rules=REGION_RULES, queries=4, seed=3
    )
    assert set(choice.rule_means) == set(REGION_RULES)
    assert choice.region_rule in REGION_RULES
    assert choice.best_mean == choice.rule_means[choice.region_rule]
    if choice.region_rule == "per_check":  # only a significant win replaces the paper's rule
        assert choice.rule_means["per_check"] < choice.rule_means["probability"]
    assert "region rule" in choice.summary_lines()[1]
    one = validate_query_leaf(problem, etas=(0.2, 1.0), pseudo_counts=(None,), queries=4, seed=3)
    assert one.region_rule == "probability"
    assert one.rule_means == {}
    assert (
        one.mean_checks
        == validate_query_leaf(
            problem, etas=(0.2, 1.0), pseudo_counts=(None,), region_rules=("probability",), queries=4, seed=3
        ).mean_checks
    )
    # Given settings skip the validation and keep the given rule.
    given = leaf_from_options(problem, eta=0.4, pseudo_counts=(5.0,), seed=0, region_rules=("per_check",))
    assert (given.eta, given.pseudo_count, given.region_rule) == (0.4, 5.0, "per_check")


def test_a_trees_own_rule_is_validated_on_its_query() -> None:
    from drd_planner.core.region_rule import REGION_RULES
    from drd_planner.planner.leaf_validation import tree_leaf_from_options

    problem = make_planar_problem(model="forest", num_worlds=150, seed=2)
    own = tree_leaf_from_options(
        problem, eta=None, pseudo_counts=(None,), seed=0, tree_options={}, region_rules=REGION_RULES
    )
    assert own.leaf is not None
    assert own.region_rule in REGION_RULES
    assert "region rule" in own.note
    given = tree_leaf_from_options(
        problem, eta=0.2, pseudo_counts=(None,), seed=0, tree_options={"region_rule": "per_check"}
    )
    assert given.leaf is None
    assert given.region_rule == "per_check"
    # eta and kappa given, the rule open: only the rule is validated, on the tree's own query
    rule_only = tree_leaf_from_options(
        problem, eta=0.2, pseudo_counts=(None,), seed=0, tree_options={}, region_rules=REGION_RULES
    )
    assert rule_only.leaf is None
    assert rule_only.region_rule in REGION_RULES
    assert "region rule" in rule_only.note
