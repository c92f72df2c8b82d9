"""Reverse shortest-path trees of a goal in every search world, batched: the same paths as one search each."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.lazysp import GraphArcs
from drd_planner.exceptions import ProblemError
from drd_planner.planner.goal_trees import GOAL_TREES_KEPT, GoalJoins, SearchWorlds, distinct_rows
from drd_planner.planner.query_library import ShortestPaths


def _grid(directed: bool) -> tuple[ExplicitGraph, np.ndarray]:
    """A 6 x 6 grid (both directions when directed) and 40 random worlds over its edges."""
    edges = []
    for i in range(6):
        for j in range(6):
            v = 6 * i + j
            if j < 5:
                edges.append((v, v + 1))
            if i < 5:
                edges.append((v, v + 6))
    pairs = np.array(edges)
    if directed:
        pairs = np.vstack([pairs, pairs[:, ::-1]])
    rng = np.random.default_rng(3)
    lengths = rng.uniform(1.0, 2.0, pairs.shape[0])
    graph = ExplicitGraph(pairs, lengths, 36, directed)
    return graph, rng.random((40, pairs.shape[0])) < 0.75


@pytest.mark.parametrize("directed", [False, True])
def test_walks_are_each_worlds_shortest_free_path(directed: bool) -> None:
    graph, x = _grid(directed)
    arcs = GraphArcs(graph)
    search = SearchWorlds(arcs, graph.lengths, x, seed=1)
    one = ShortestPaths(arcs, graph.lengths)
    for goal, start in ((35, 0), (7, 30), (0, 35)):
        tree = search.tree(goal)
        for c, walk in enumerate(tree.walks(np.full(search.num_worlds, start))):
            reference = one.path(start, goal, x[search.worlds[c]])
            assert (walk is None) == (reference is None)
            if walk is None:
                continue
            path = arcs.edge_of(walk[:-1], walk[1:])
            assert walk[0] == start and walk[-1] == goal and x[search.worlds[c], path].all()
            assert graph.lengths[path].sum() == pytest.approx(graph.lengths[reference].sum())


def test_trees_are_kept_per_goal_and_a_joined_goal_leaves_the_graph_as_it_was() -> None:
    graph, x = _grid(False)
    search = SearchWorlds(GraphArcs(graph), graph.lengths, x, seed=1)
    first = search.tree(20)
    assert search.tree(20) is first
    for goal in range(GOAL_TREES_KEPT + 1):
        search.tree(goal)
    assert search.tree(20) is not first  # dropped, rebuilt with the same numbers
    assert np.array_equal(search.tree(20).dist, first.dist)
    w = search.num_worlds
    joins = GoalJoins(np.array([14, 21]), np.array([0.5, 0.25]), np.tile([True, False], (w, 1)))
    joined = search.joined_tree(joins)
    assert joined.goal == 36  # the extra vertex of each block
    assert np.allclose(joined.dist[:, 14], 0.5)  # only the first join is free
    assert np.array_equal(search.tree(20).dist, first.dist)  # the shared graph is unchanged
    with pytest.raises(ProblemError, match="join outcomes"):
        search.joined_tree(GoalJoins(np.array([14]), np.array([1.0]), np.ones((w + 1, 1), dtype=bool)))


def test_distinct_rows_are_found_exactly() -> None:
    rng = np.random.default_rng(0)
    base = rng.random((30, 100)) < 0.5
    x = base[rng.integers(0, 30, size=200)]
    first = distinct_rows(x)
    _, reference = np.unique(x, axis=0, return_index=True)
    assert np.array_equal(first, np.sort(reference))
    assert distinct_rows(np.zeros((0, 5), dtype=bool)).size == 0
