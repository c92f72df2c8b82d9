"""Tests of the region rules: which path BiSECt and the DiRECt tree try to prove next."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from drd_planner.core.bisect import Bisect
from drd_planner.core.library import PathLibrary
from drd_planner.core.online_tree import LazyDirectTree
from drd_planner.core.region_rule import (
    REGION_RULES,
    check_region_rule,
    expected_proof_costs,
    node_region_path,
    region_scores,
)
from drd_planner.core.tree import build_tree
from drd_planner.data.planar_problem import make_planar_problem
from drd_planner.exceptions import ProblemError


def _resolve_cost(order: list[int], theta: np.ndarray, costs: np.ndarray) -> float:
    """Expected cost of checking ``order`` until the first blocked edge (brute force)."""
    total, reach = 0.0, 1.0
    for e in order:
        total += reach * costs[e]
        reach *= theta[e]
    return total


def test_expected_proof_cost_is_the_best_order_of_each_paths_untested_edges() -> None:
    rng = np.random.default_rng(4)
    num_edges = 12
    paths = [rng.choice(num_edges, size=int(rng.integers(1, 6)), replace=False) for _ in range(7)]
    library = PathLibrary(paths, num_edges)
    theta = rng.uniform(0.05, 0.95, num_edges)
    costs = rng.uniform(0.5, 3.0, num_edges)
    done = np.zeros(num_edges, dtype=bool)
    done[[1, 5]] = True
    rows = np.ones(len(paths), dtype=bool)
    rows[3] = False
    csr = library.incidence
    got = expected_proof_costs(csr.indptr, csr.indices, theta, costs, done, rows)
    for i, path in enumerate(paths):
        todo = [int(e) for e in path if not done[e]]
        if not rows[i] or not todo:
            assert got[i] == 0.0
            continue
        best = min(_resolve_cost(list(p), theta, costs) for p in itertools.permutations(todo))
        assert got[i] == pytest.approx(best, rel=1e-12)


def test_per_check_prefers_a_short_path_that_is_almost_as_likely() -> None:
    # Path 0: 12 edges, free with probability 0.5; path 1: 3 edges, free with probability 0.45.
    long_theta, short_theta = 0.5 ** (1 / 12), 0.45 ** (1 / 3)
    library = PathLibrary([np.arange(12), np.arange(12, 15)], 15)
    theta = np.r_[np.full(12, long_theta), np.full(3, short_theta)]
    costs = np.ones(15)
    log_p = np.log([0.5, 0.45])
    csr = library.incidence
    proof = expected_proof_costs(csr.indptr, csr.indices, theta, costs, np.zeros(15, bool), np.ones(2, bool))
    assert int(np.argmax(region_scores("probability", log_p, proof))) == 0
    assert int(np.argmax(region_scores("per_check", log_p, proof))) == 1
    # BiSECt follows its rule: the paper's rule checks the long path, the new one the short path.
    paper = Bisect(library, theta, costs)
    assert paper.select() in range(12)
    cost_aware = Bisect(library, theta, costs, region_rule="per_check")
    assert cost_aware.select() in range(12, 15)
    # Dead paths never win, whatever their length.
    dead = region_scores("per_check", np.array([-np.inf, np.log(0.1)]), np.array([0.5, 9.0]))
    assert int(np.argmax(dead)) == 1


def test_a_tree_node_picks_its_path_by_the_rule() -> None:
    library = PathLibrary([np.arange(12), np.arange(12, 15)], 15)
    support = np.array([50.0, 45.0])
    free = np.r_[np.full(12, 0.95), np.full(3, 0.75)]
    csr = library.incidence
    args = ((csr.indptr, csr.indices), np.ones(15), np.zeros(15, bool))
    assert node_region_path("probability", support, free, *args) == 0
    assert node_region_path("per_check", support, free, *args) == 1
    # Edges already checked on the branch cost nothing: with 10 of its 12 edges done, the long path wins.
    checked = np.zeros(15, bool)
    checked[:10] = True
    assert node_region_path("per_check", support, free, args[0], args[1], checked) == 0
    assert node_region_path("per_check", np.zeros(2), free, *args) is None


@pytest.mark.parametrize("rule", REGION_RULES)
def test_online_and_offline_trees_agree_under_each_rule(rule: str) -> None:
    problem = make_planar_problem(model="forest", num_worlds=200, seed=3)
    worlds = problem.require_worlds()
    offline = build_tree(problem, progress=False, region_rule=rule)
    online = LazyDirectTree(worlds.X[worlds.train_ids], problem.library, problem.edge_costs, region_rule=rule)
    queue = [(0, 0)]
    while queue:
        a, b = queue.pop()
        assert online.node_edge(b) == offline.node_edge(a)
        for free in (False, True):
            ca, cb = offline.node_child(a, free), online.node_child(b, free)
            assert (ca < 0) == (cb < 0)
            if ca >= 0:
                queue.append((ca, cb))
    assert offline.info["region_rule"] == rule


def test_the_rules_give_different_trees_somewhere() -> None:
    problem = make_planar_problem(model="forest", num_worlds=200, seed=3)
    paper = build_tree(problem, progress=False)
    cost_aware = build_tree(problem, progress=False, region_rule="per_check")
    assert [paper.node_edge(n) for n in range(paper.num_nodes)] != [
        cost_aware.node_edge(n) for n in range(cost_aware.num_nodes)
    ]


def test_unknown_rules_are_refused_with_the_choices() -> None:
    assert check_region_rule("per_check") == "per_check"
    with pytest.raises(ProblemError, match="unknown region rule 'cheapest'; known: probability, per_check"):
        check_region_rule("cheapest")
    library = PathLibrary([np.arange(2)], 2)
    with pytest.raises(ProblemError, match="unknown region rule"):
        Bisect(library, np.full(2, 0.5), np.ones(2), region_rule="cheapest")


def test_a_new_bias_reorders_the_proofs() -> None:
    # The sorted proof order belongs to one bias: after set_theta the rule sees the new probabilities.
    library = PathLibrary([np.arange(12), np.arange(12, 15)], 15)
    theta = np.r_[np.full(12, 0.5 ** (1 / 12)), np.full(3, 0.45 ** (1 / 3))]
    bisect = Bisect(library, theta, np.ones(15), region_rule="per_check")
    assert bisect.select() in range(12, 15)
    bisect.set_theta(np.r_[np.full(12, 0.5 ** (1 / 12)), np.full(3, 0.05)])
    assert bisect.select() in range(12)
