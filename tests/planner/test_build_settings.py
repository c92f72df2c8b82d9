"""Tests of the typed tree-build settings: the keyword arguments they give and the leaf they choose."""

from __future__ import annotations

from drd_planner.core.region_rule import DEFAULT_REGION_RULE
from drd_planner.core.tree import DEFAULT_EXPAND_THRESHOLD, build_tree
from drd_planner.data.planar_problem import make_planar_problem
from drd_planner.planner.build_settings import LeafChoice, TreeSettings


def test_tree_settings_are_the_keyword_arguments_of_build_tree() -> None:
    kwargs = TreeSettings(expand_threshold=0.2, colouring=True, top_regions=3, max_prob_region=False).kwargs()
    assert kwargs == {
        "expand_threshold": 0.2,
        "colouring": True,
        "top_regions": 3,
        "max_prob_region": False,
        "region_rule": DEFAULT_REGION_RULE,
    }
    assert TreeSettings().kwargs()["expand_threshold"] == DEFAULT_EXPAND_THRESHOLD
    problem = make_planar_problem(num_worlds=40, seed=1)
    assert build_tree(problem, progress=False, **TreeSettings().kwargs()).num_nodes >= 1


def test_a_fully_given_leaf_is_taken_as_given() -> None:
    problem = make_planar_problem(num_worlds=40, seed=1)
    choice = LeafChoice(eta=0.3, pseudo_counts=(2.0,), region_rules=(DEFAULT_REGION_RULE,))
    leaf = choice.prior_leaf(problem)
    assert (leaf.eta, leaf.pseudo_count, leaf.region_rule) == (0.3, 2.0, DEFAULT_REGION_RULE)
    assert "given" in leaf.note
    tree_leaf = choice.tree_leaf(problem, TreeSettings())
    assert tree_leaf.leaf is None
    assert tree_leaf.region_rule == DEFAULT_REGION_RULE
