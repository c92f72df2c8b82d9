"""The offline DiRECt tree: structure, expansion rule, leaf bias, and the online walk."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.core.direct import DirectSelector
from drd_planner.core.policies import DirectBisectPolicy, DirectOnlyPolicy
from drd_planner.core.problem import Problem
from drd_planner.core.tree import NO_CHILD, NO_EDGE, DecisionTree, build_tree, greedy_cover_regions
from drd_planner.data.planar_problem import make_planar_problem


@pytest.fixture(scope="module")
def problem() -> Problem:
    return make_planar_problem(num_worlds=200, max_paths=60, seed=5)


def _node_worlds(tree: DecisionTree, X: np.ndarray) -> list[np.ndarray]:
    """Recompute each node's consistent training worlds from the edges on its root path."""
    worlds: list[np.ndarray] = [np.array([], dtype=np.int64)] * tree.num_nodes
    worlds[0] = np.arange(X.shape[0])
    for node in range(tree.num_nodes):
        edge = tree.edge[node]
        for outcome in (0, 1):
            child = tree.children[node, outcome]
            if child != NO_CHILD:
                active = worlds[node]
                worlds[child] = active[X[active, edge] == bool(outcome)]
    return worlds


@pytest.mark.parametrize(
    "options",
    [
        {},
        {"max_prob_region": False},
        {"top_regions": 5, "max_prob_region": False},
        {"colouring": True, "max_prob_region": False},
    ],
)
def test_tree_structure_and_expansion_rule(problem: Problem, options: dict[str, object]) -> None:
    worlds = problem.require_worlds()
    X = worlds.X[worlds.train_ids]
    n = X.shape[0]
    tree = build_tree(problem, progress=False, expand_threshold=0.05, **options)  # type: ignore[arg-type]
    node_worlds = _node_worlds(tree, X)
    assert tree.num_nodes > 3
    for node in range(tree.num_nodes):
        active = node_worlds[node]
        assert tree.num_active[node] == active.size
        assert tree.active_fraction[node] == pytest.approx(active.size / n)
        has_edge = tree.edge[node] != NO_EDGE
        assert has_edge == (tree.children[node] != NO_CHILD).all()
        if has_edge:
            assert node == 0 or tree.active_fraction[node] >= 0.05  # only big nodes are expanded
            a, b = tree.children[node]
            assert tree.num_active[a] + tree.num_active[b] == active.size
        if active.size:
            lib = tree.library_edges
            np.testing.assert_allclose(tree.free_fraction[node], X[active][:, lib].mean(0), rtol=1e-6)
    # every root-to-node path checks distinct edges
    on_path: dict[int, list[int]] = {0: []}
    for node in range(tree.num_nodes):
        if tree.edge[node] != NO_EDGE:
            assert tree.edge[node] not in on_path[node]
            for child in tree.children[node]:
                on_path[int(child)] = [*on_path[node], int(tree.edge[node])]
    assert tree.depth() >= 2


def test_unrestricted_tree_nodes_pick_direct_choice(problem: Problem) -> None:
    worlds = problem.require_worlds()
    X = worlds.X[worlds.train_ids]
    R = worlds.R[worlds.train_ids]
    tree = build_tree(problem, progress=False, max_prob_region=False)
    selector = DirectSelector(X, R, problem.edge_costs)
    node_worlds = _node_worlds(tree, X)
    for node in range(tree.num_nodes):
        choice = selector.select(node_worlds[node])
        if tree.edge[node] != NO_EDGE:
            assert choice is not None
            assert choice.edge == tree.edge[node]


def test_bias_formula_and_best_path(problem: Problem) -> None:
    tree = build_tree(problem, progress=False)
    theta = tree.bias(0, alpha=0.99)
    worlds = problem.require_worlds()
    X = worlds.X[worlds.train_ids]
    lib = tree.library_edges
    np.testing.assert_allclose(theta[lib], 0.99 * X[:, lib].mean(0) + 0.005, rtol=1e-6)
    off = np.setdiff1d(np.arange(problem.num_edges), lib)
    assert np.all(theta[off] == 0.5)
    support = worlds.R[worlds.train_ids].sum(0)
    assert support[tree.best_path[0]] == support.max()


def test_greedy_cover_regions() -> None:
    R = np.array([[1, 1, 0], [1, 0, 0], [0, 0, 1], [0, 1, 0]], dtype=bool)
    np.testing.assert_array_equal(greedy_cover_regions(R, np.ones(4), 3), [0, 1, 2])
    np.testing.assert_array_equal(greedy_cover_regions(R, np.array([1, 1, 5, 1.0]), 1), [2])
    assert greedy_cover_regions(np.zeros((2, 2), dtype=bool), np.ones(2), 3).size == 0


def test_tree_is_deterministic(problem: Problem) -> None:
    a = build_tree(problem, progress=False)
    b = build_tree(problem, progress=False)
    np.testing.assert_array_equal(a.edge, b.edge)
    np.testing.assert_array_equal(a.children, b.children)


def test_direct_bisect_switches_at_eta(problem: Problem) -> None:
    tree = build_tree(problem, progress=False)
    worlds = problem.require_worlds()
    for world in worlds.test_ids[:10]:
        policy = DirectBisectPolicy(tree, problem.library, problem.edge_costs, eta=0.2)
        x = worlds.X[world]
        node = 0
        while policy.stage == "tree":
            edge = policy.select()
            assert edge == tree.edge[node]
            assert tree.active_fraction[node] > 0.2
            policy.observe(edge, bool(x[edge]))
            node = int(tree.children[node, int(x[edge])])
        assert policy.switch_node == node
        assert tree.active_fraction[node] <= 0.2 or tree.edge[node] == NO_EDGE
    # eta = 1 switches at the root; eta = 0 walks to a leaf
    assert DirectBisectPolicy(tree, problem.library, problem.edge_costs, eta=1.0).stage == "bisect"


def test_direct_only_walks_to_leaf_then_checks_best_path(problem: Problem) -> None:
    tree = build_tree(problem, progress=False)
    worlds = problem.require_worlds()
    x = worlds.X[worlds.test_ids[0]]
    policy = DirectOnlyPolicy(tree, problem.library, seed=1)
    node = 0
    while (edge := policy.select()) is not None and policy.stage == "tree":
        policy.observe(edge, bool(x[edge]))
        node = int(tree.children[node, int(x[edge])])
    assert tree.edge[node] == NO_EDGE
