"""The union's shortest path is read as a world's path exactly where it is that world's only shortest path."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.lazysp import GraphArcs
from drd_planner.planner.query_library import ShortestPaths
from drd_planner.planner.union_paths import NO_HOP, JoinMotions, UnionTree, follows_union
from drd_planner.planner.world_blocks import WorldBlocks
from tests.conftest import grid_graph


def _grid(lengths: str) -> tuple[ExplicitGraph, np.ndarray]:
    """A 5 x 5 grid with random or equal edge lengths, and 30 random worlds."""
    rng = np.random.default_rng(5)
    graph = grid_graph(5, rng, equal_lengths=lengths == "equal")
    return graph, rng.random((30, graph.num_edges)) < 0.8


def _setup(graph: ExplicitGraph, x: np.ndarray) -> tuple[GraphArcs, np.ndarray, WorldBlocks]:
    arcs = GraphArcs(graph)
    arc_length = np.asarray(graph.lengths)[arcs.edge]
    return arcs, arc_length, WorldBlocks(arcs, arc_length, x[:, arcs.edge], 4)


def _all_shortest(graph: ExplicitGraph, free: np.ndarray, start: int, goal: int) -> tuple[float, int]:
    """A world's shortest free distance and how many shortest paths it has (counted over its tight arcs).

    (A tied arc into a dead end is not counted here; the shortcut, which looks only at the union, withholds there.)
    """
    one = ShortestPaths(GraphArcs(graph), graph.lengths)
    to_goal = np.array([_length(graph, one.path(v, goal, free)) for v in range(graph.num_vertices)])
    count = np.zeros(graph.num_vertices)
    count[goal] = 1
    for v in np.argsort(to_goal):
        if v == goal or not np.isfinite(to_goal[v]):
            continue
        for e in np.flatnonzero(free & ((graph.edges[:, 0] == v) | (graph.edges[:, 1] == v))):
            w = graph.edges[e, 1] if graph.edges[e, 0] == v else graph.edges[e, 0]
            if abs(graph.lengths[e] + to_goal[w] - to_goal[v]) < 1e-9:
                count[v] += count[w]
    return float(to_goal[start]), int(count[start])


def _length(graph: ExplicitGraph, path: np.ndarray | None) -> float:
    return np.inf if path is None else float(np.asarray(graph.lengths)[path].sum())


@pytest.mark.parametrize("lengths", ["random", "equal"])
def test_a_world_follows_the_union_only_where_the_unions_path_is_its_only_shortest_one(lengths: str) -> None:
    graph, x = _grid(lengths)
    arcs, arc_length, blocks = _setup(graph, x)
    anywhere = x.any(axis=0)
    flagged = 0
    for start, goal in ((0, 24), (4, 20), (12, 0), (7, 17)):
        union = blocks.union_tree(goal)
        walk = union.walk(start)
        path = arcs.edge_of(walk[:-1], walk[1:])
        follows = follows_union(union, start, arcs, arc_length, x, anywhere)
        for w in range(x.shape[0]):
            distance, ways = _all_shortest(graph, x[w], start, goal)
            unique_union_path = bool(x[w, path].all()) and ways == 1 and distance == pytest.approx(union.dist[start])
            assert not follows[w] or unique_union_path, (start, goal, w)
            if lengths == "random":  # no ties: every world with the union's path free follows it
                assert follows[w] == unique_union_path, (start, goal, w)
        flagged += int(follows.sum())
    assert flagged > 0


def test_a_tied_alternative_free_in_a_world_withholds_the_shortcut() -> None:
    # A square 0-1-3 / 0-2-3 of equal lengths: two shortest paths from 0 to 3.
    graph = ExplicitGraph(np.array([[0, 1], [1, 3], [0, 2], [2, 3]]), np.ones(4), 4, False)
    x = np.array([[1, 1, 1, 1], [1, 1, 0, 1], [0, 1, 1, 1]], dtype=bool)
    arcs, arc_length, blocks = _setup(graph, x)
    union = blocks.union_tree(3)
    follows = follows_union(union, 0, arcs, arc_length, x, x.any(axis=0))
    walk = union.walk(0)
    via_one = walk[1] == 1  # which of the two the union's tree took
    # World 0 has both paths (tie: no shortcut); worlds 1 and 2 have one each: read where it is the union's.
    assert follows.tolist() == [False, bool(via_one), not via_one]


def test_an_off_graph_goals_motions_are_arcs_of_the_path() -> None:
    graph, x = _grid("random")
    arcs, arc_length, blocks = _setup(graph, x)
    rng = np.random.default_rng(0)
    joins = JoinMotions(np.array([18, 23, 24]), np.array([0.4, 0.3, 0.2]), rng.random((30, 3)) < 0.6)
    goal = blocks.block - 1
    union = blocks.union_tree(goal, joins)
    assert union.hop[goal] == NO_HOP
    assert union.dist[goal] == 0.0
    follows = follows_union(union, 0, arcs, arc_length, x, x.any(axis=0), joins)
    walk = union.walk(0)
    last = int(np.flatnonzero(joins.vertices == walk[-2])[0])
    # Where a world follows, the last motion is free there and the graph part of the walk too.
    path = arcs.edge_of(walk[:-2], walk[1:-1])
    assert follows.any()
    assert (joins.free[follows, last]).all()
    assert x[np.ix_(follows, path)].all()
    # A world where that motion is blocked never follows.
    assert not (follows & ~joins.free[:, last]).any()


def test_an_unreachable_start_follows_nowhere() -> None:
    graph, x = _grid("random")
    arcs, arc_length, _ = _setup(graph, x)
    tree = UnionTree(24, np.full(26, np.inf), np.full(26, NO_HOP, dtype=np.int32))
    assert tree.walk(0).size == 0
    assert not follows_union(tree, 0, arcs, arc_length, x, x.any(axis=0)).any()
