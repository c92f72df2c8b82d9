"""Several worlds' reverse trees in one search, over just the vertices asked for: each world's own distances."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse.csgraph import dijkstra

from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.lazysp import GraphArcs
from drd_planner.planner import world_blocks
from drd_planner.planner.query_library import ShortestPaths
from drd_planner.planner.union_paths import NO_HOP, JoinMotions
from drd_planner.planner.world_blocks import WorldBlocks


def _setup(directed: bool) -> tuple[ExplicitGraph, np.ndarray, GraphArcs, WorldBlocks]:
    rng = np.random.default_rng(2)
    n = 30
    pairs = np.array([(u, v) for u in range(n) for v in range(u + 1, n) if rng.random() < 0.2])
    if directed:
        pairs = np.vstack([pairs, pairs[:, ::-1]])
    graph = ExplicitGraph(pairs, rng.uniform(0.5, 2.0, len(pairs)), n, directed)
    x = rng.random((12, len(pairs))) < 0.7
    arcs = GraphArcs(graph)
    return graph, x, arcs, WorldBlocks(arcs, np.asarray(graph.lengths)[arcs.edge], x[:, arcs.edge], 4)


def _distances_to(graph: ExplicitGraph, free: np.ndarray, goal: int) -> np.ndarray:
    one = ShortestPaths(GraphArcs(graph), graph.lengths)
    out = np.full(graph.num_vertices, np.inf)
    for v in range(graph.num_vertices):
        path = one.path(v, goal, free)
        if path is not None:
            out[v] = float(np.asarray(graph.lengths)[path].sum())
    return out


@pytest.mark.parametrize("directed", [False, True])
def test_a_search_of_some_worlds_gives_each_its_own_distances_and_next_hops(directed: bool) -> None:
    graph, x, arcs, blocks = _setup(directed)
    goal = 3
    union = blocks.union_tree(goal)
    anywhere = x.any(axis=0)
    assert np.allclose(union.dist[:-1], _distances_to(graph, anywhere, goal), equal_nan=False)
    worlds = np.array([7, 2, 9])
    vertices, dist, hop = blocks.search(union, worlds, limit=np.inf)
    for r, w in enumerate(worlds.tolist()):
        reference = _distances_to(graph, x[w], goal)
        row = np.full(blocks.block, np.inf)
        row[vertices] = dist[r]
        assert np.allclose(row[:-1], reference)
        for i, v in enumerate(vertices.tolist()):  # a next hop is a free arc on a shortest path
            if v != goal and np.isfinite(dist[r, i]):
                e = arcs.edge_of(np.array([v]), np.array([hop[r, i]]))[0]
                assert x[w, e]
                assert graph.lengths[e] + row[hop[r, i]] == pytest.approx(row[v])
            elif v == goal:
                assert hop[r, i] == NO_HOP


def test_a_limited_search_knows_what_is_within_the_limit() -> None:
    graph, x, _, blocks = _setup(False)
    union = blocks.union_tree(0)
    limit = float(np.median(union.dist[np.isfinite(union.dist)]))
    vertices, dist, _ = blocks.search(union, np.array([4]), limit=limit)
    assert (union.dist[vertices] <= limit).all()  # only vertices some world could reach within the limit
    reference = _distances_to(graph, x[4], 0)
    inside = reference[vertices[:-1] if vertices[-1] == blocks.block - 1 else vertices] <= limit
    got = dist[0, : inside.size]
    assert np.allclose(got[inside], reference[vertices[: inside.size]][inside])
    assert (got[~inside] > limit).all()
    # Only some vertices asked for: the goal's own part of the graph.
    within = np.zeros(blocks.block, dtype=bool)
    within[[0, 1, 2]] = True
    vertices, dist, _ = blocks.search(union, np.array([4]), limit=np.inf, within=within)
    assert vertices.tolist() == [0, 1, 2]


def test_an_off_graph_goal_is_searched_through_its_motions_and_distances_from_a_start_bound_the_worlds() -> None:
    graph, x, _, blocks = _setup(False)
    goal = blocks.block - 1
    joins = JoinMotions(np.array([5, 6]), np.array([0.3, 0.1]), np.array([[True, False]] * 12))
    union = blocks.union_tree(goal, joins)
    vertices, dist, hop = blocks.search(union, np.array([0, 1]), limit=np.inf, joins=joins)
    at = {v: i for i, v in enumerate(vertices.tolist())}
    assert dist[0, at[5]] == pytest.approx(0.3)  # only the first motion is free
    assert hop[0, at[5]] == goal
    assert np.isfinite(dist[:, at[6]]).all()
    assert (dist[:, at[6]] > 0.1).all()
    ahead = blocks.union_from(np.array([2]), np.zeros(1), np.ones(1, dtype=bool))
    forward = ShortestPaths(GraphArcs(graph), graph.lengths)
    for v in (0, 9, 17):
        path = forward.path(2, v, x.any(axis=0))
        assert ahead[v] == pytest.approx(np.inf if path is None else float(np.asarray(graph.lengths)[path].sum()))
    # An off-graph start's motions: each vertex's distance through the best of them.
    two = blocks.union_from(np.array([2, 9]), np.array([1.0, 0.5]), np.array([True, False]))
    assert two[2] == pytest.approx(1.0)
    assert two[9] == pytest.approx(1.0 + ahead[9])


@pytest.mark.parametrize("directed", [False, True])
def test_worlds_alike_on_the_searched_arcs_are_searched_once_and_get_their_own_rows(
    directed: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Repeated worlds share one block of the search, and each still gets the rows of its own search."""
    sources: list[int] = []

    def counting(*args: object, **kwargs: object) -> object:
        sources.append(np.size(kwargs["indices"]))
        return dijkstra(*args, **kwargs)

    monkeypatch.setattr(world_blocks, "dijkstra", counting)
    graph, x, arcs, _ = _setup(directed)
    x = x[[0, 1, 0, 2, 1, 0]].copy()
    x[5, 0] = not x[5, 0]  # world 5 differs from world 0 in one edge only
    blocks = WorldBlocks(arcs, np.asarray(graph.lengths)[arcs.edge], x[:, arcs.edge], 4)
    union = blocks.union_tree(3)
    sources.clear()  # the union's own search
    together = blocks.search(union, np.arange(6), limit=np.inf)
    assert sources == [4]  # worlds 0, 1, 3 and 5 (2 is 0, 4 is 1)
    for w in range(6):
        alone = blocks.search(union, np.array([w]), limit=np.inf)
        assert np.array_equal(alone[0], together[0])
        assert np.array_equal(alone[1][0], together[1][w])
        assert np.array_equal(alone[2][0], together[2][w])
    assert np.array_equal(together[1][0], together[1][2])
    assert not np.array_equal(together[1][0], together[1][1])


def test_the_block_graph_holds_each_blocks_free_arcs_in_its_own_rows_and_columns() -> None:
    rng = np.random.default_rng(5)
    size = 7
    row = np.sort(rng.integers(1, size - 1, 40))  # rows 0 and size - 1 have no arcs
    col = rng.integers(0, size, 40)
    length = rng.uniform(0.5, 2.0, 40)
    free = rng.random((3, 40)) < 0.6
    free[1] = False  # a block with no free arc
    graph = world_blocks._block_graph(free, row, col, length, size)
    blocks, arcs = np.nonzero(free)
    # Duplicate arcs (the same head and tail twice) are both kept in the CSR; the dense form sums them.
    dense = np.zeros((3 * size, 3 * size))
    np.add.at(dense, (row[arcs] + blocks * size, col[arcs] + blocks * size), length[arcs])
    assert np.allclose(graph.toarray(), dense)
    assert graph.nnz == int(free.sum())
    assert graph.indptr[size : 2 * size + 1].tolist() == [graph.indptr[size]] * (size + 1)  # block 1: empty rows
