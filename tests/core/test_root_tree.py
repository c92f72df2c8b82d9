"""The one-node tree of eta = 1: the same root bias and posterior worlds as the DiRECt tree grown online."""

from __future__ import annotations

import numpy as np

from drd_planner.core.library import PathLibrary
from drd_planner.core.online_tree import LazyDirectTree
from drd_planner.core.policies import DirectBisectPolicy
from drd_planner.core.root_tree import RootTree
from drd_planner.core.tree import NO_CHILD, NO_EDGE


def _problem(seed: int) -> tuple[np.ndarray, PathLibrary, np.ndarray]:
    rng = np.random.default_rng(seed)
    x = rng.random((60, 12)) < 0.7
    library = PathLibrary.from_sequences([[0, 1, 2], [3, 4, 2], [5, 6], [7, 8, 9, 10]], 12)
    return x, library, rng.uniform(0.5, 2.0, 12)


def test_the_root_is_the_lazy_trees_root() -> None:
    for seed in range(5):
        x, library, costs = _problem(seed)
        lazy = LazyDirectTree(x, library, costs, region_rule="probability")
        root = RootTree(x[:, library.library_edges], library, region_rule="probability")
        assert np.array_equal(root.bias(0, alpha=0.97), lazy.bias(0, alpha=0.97))
        assert root.node_fraction(0) == lazy.node_fraction(0) == 1.0
        assert root.node_edge(0) == NO_EDGE
        assert root.node_child(0, True) == NO_CHILD
        assert (root.num_edges, root.num_paths, root.num_nodes) == (12, 4, 1)
        ours, theirs = root.training_outcomes, lazy.training_outcomes
        assert np.array_equal(ours.world_free, theirs.world_free)
        assert np.array_equal(ours.marginal, theirs.marginal)


def test_direct_bisect_at_eta_one_checks_the_same_edges_on_both_trees() -> None:
    for seed in range(5):
        x, library, costs = _problem(seed)
        world = x[seed]
        runs = []
        for tree in (
            LazyDirectTree(x, library, costs, region_rule="per_check"),
            RootTree(x[:, library.library_edges], library, region_rule="per_check"),
        ):
            policy = DirectBisectPolicy(tree, library, costs, eta=1.0, pseudo_count=5.0)
            checked = []
            while (edge := policy.select()) is not None and len(checked) < 12:
                checked.append(edge)
                policy.observe(edge, bool(world[edge]))
            runs.append(checked)
        assert runs[0] == runs[1]
