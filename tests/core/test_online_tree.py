"""The DiRECt tree grown online makes exactly the offline tree's checks (same worlds, library, seed)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import gccd_folder, gccd_graph_datasets

from drd_planner.core.episode import TableOracle, run_episode
from drd_planner.core.online_tree import LazyDirectTree
from drd_planner.core.policies import DirectBisectPolicy
from drd_planner.core.tree import NO_EDGE, build_tree
from drd_planner.data.gccd import load_gccd_folder
from drd_planner.data.planar_problem import make_planar_problem
from drd_planner.exceptions import ProblemError

#: Test worlds per dataset; eta small enough that the tree (not only BiSECt) chooses checks.
WORLDS = 6


def _checks(tree: object, problem: object, world: int, *, eta: float, kappa: float | None) -> list[int]:
    lib, costs, worlds = problem.library, problem.edge_costs, problem.require_worlds()  # type: ignore[attr-defined]
    policy = DirectBisectPolicy(tree, lib, costs, eta=eta, pseudo_count=kappa)  # type: ignore[arg-type]
    result = run_episode(lib, costs, policy, TableOracle(worlds.X[world]))
    return [c.edge for c in result.checks]


@pytest.mark.parametrize("name", gccd_graph_datasets())
def test_online_tree_checks_equal_offline_tree_on_each_dataset_query(name: str) -> None:
    problem = load_gccd_folder(gccd_folder(name))
    worlds = problem.require_worlds()
    offline = build_tree(problem, progress=False)
    online = LazyDirectTree(worlds.X[worlds.train_ids], problem.library, problem.edge_costs)
    used_tree = False
    for world in worlds.test_ids[:WORLDS].tolist():
        for eta, kappa in ((0.05, None), (0.2, 5.0)):
            want = _checks(offline, problem, world, eta=eta, kappa=kappa)
            got = _checks(online, problem, world, eta=eta, kappa=kappa)
            assert got == want, f"{name} world {world} eta {eta}"
            used_tree |= offline.edge[0] != NO_EDGE
    assert used_tree
    # Only the branches taken were grown, and every grown node agrees with the offline tree's rule.
    assert online.num_nodes <= offline.num_nodes
    for node in range(1, online.num_nodes):
        assert 0.0 <= online.node_fraction(node) <= 1.0


def test_lazy_nodes_mirror_offline_nodes_on_a_planar_problem() -> None:
    problem = make_planar_problem(model="forest", num_worlds=200, seed=3)
    worlds = problem.require_worlds()
    offline = build_tree(problem, progress=False)
    online = LazyDirectTree(worlds.X[worlds.train_ids], problem.library, problem.edge_costs)
    # Walk both trees breadth-first side by side: edges, fractions and leaf biases agree node for node.
    queue = [(0, 0)]
    while queue:
        a, b = queue.pop()
        assert online.node_edge(b) == offline.node_edge(a)
        assert online.node_fraction(b) == pytest.approx(offline.node_fraction(a), abs=0)
        np.testing.assert_array_equal(online.bias(b), offline.bias(a))
        for free in (False, True):
            ca, cb = offline.node_child(a, free), online.node_child(b, free)
            assert (ca < 0) == (cb < 0)
            if ca >= 0:
                queue.append((ca, cb))
    assert online.num_nodes == offline.num_nodes


def test_node_cap_turns_nodes_into_leaves() -> None:
    problem = make_planar_problem(model="forest", num_worlds=120, seed=1)
    worlds = problem.require_worlds()
    tree = LazyDirectTree(worlds.X[worlds.train_ids], problem.library, problem.edge_costs, max_nodes=3)
    assert tree.node_edge(0) != NO_EDGE
    assert tree.num_nodes == 3
    assert tree.node_edge(1) == NO_EDGE
    assert tree.node_edge(2) == NO_EDGE


def test_needs_training_worlds_over_the_library_edges() -> None:
    problem = make_planar_problem(model="one_wall", num_worlds=50, seed=0)
    with pytest.raises(ProblemError, match="training outcomes"):
        LazyDirectTree(np.zeros((0, problem.num_edges), dtype=bool), problem.library, problem.edge_costs)
