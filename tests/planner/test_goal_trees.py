"""Reverse shortest-path trees of a goal in every search world, batched: the same paths as one search each."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.lazysp import GraphArcs
from drd_planner.exceptions import ProblemError
from drd_planner.planner import goal_trees
from drd_planner.planner.goal_trees import GOAL_TREES_KEPT, JoinMotions, SearchWorlds
from drd_planner.planner.query_graph import Joins
from drd_planner.planner.query_library import ShortestPaths, library_paths
from tests.conftest import grid_graph


def _grid(directed: bool) -> tuple[ExplicitGraph, np.ndarray]:
    """A 6 x 6 grid (both directions when directed) and 40 random worlds over its edges."""
    rng = np.random.default_rng(3)
    graph = grid_graph(6, rng, directed=directed)
    return graph, rng.random((40, graph.num_edges)) < 0.75


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
            assert walk[0] == start
            assert walk[-1] == goal
            assert x[search.worlds[c], path].all()
            assert graph.lengths[path].sum() == pytest.approx(graph.lengths[reference].sum())


def test_trees_are_kept_per_goal_and_a_joined_goal_leaves_the_graph_as_it_was() -> None:
    graph, x = _grid(False)
    search = SearchWorlds(GraphArcs(graph), graph.lengths, x, seed=1)
    first = search.tree(20)
    assert search.tree(20) is first
    for goal in range(GOAL_TREES_KEPT + 1):
        search.tree(goal)
    assert search.tree(20) is not first  # dropped, rebuilt with the same numbers
    every = np.arange(36)
    assert np.array_equal(search.tree(20).dist_at(every), first.dist_at(every))
    w = search.num_worlds
    joins = JoinMotions(np.array([14, 21]), np.array([0.5, 0.25]), np.tile([True, False], (w, 1)))
    joined = search.joined_tree(joins)
    assert joined.goal == 36  # the extra vertex of each block
    assert np.allclose(joined.dist_at(np.array([14]))[:, 0], 0.5)  # only the first join is free
    assert np.array_equal(search.tree(20).dist_at(every), first.dist_at(every))  # the shared graph is unchanged
    with pytest.raises(ProblemError, match="join outcomes"):
        search.joined_tree(JoinMotions(np.array([14]), np.array([1.0]), np.ones((w + 1, 1), dtype=bool)))


def test_a_joined_goals_union_is_searched_once_for_its_probe_and_its_library(monkeypatch: pytest.MonkeyPatch) -> None:
    graph, x = _grid(False)
    search = SearchWorlds(GraphArcs(graph), graph.lengths, x, seed=1)
    w = search.num_worlds
    joins = JoinMotions(np.array([14, 21]), np.array([0.5, 0.25]), np.tile([True, False], (w, 1)))
    made = []
    union_tree = search._blocks.union_tree
    monkeypatch.setattr(search._blocks, "union_tree", lambda *a: made.append(a) or union_tree(*a))
    walk, _ = search.union_walk(joins, 0)
    same = JoinMotions(joins.vertices.copy(), joins.lengths.copy(), joins.free.copy())
    walks = search.walks_from(same, 0)
    assert len(made) == 1  # the probe's union path, then the library: one search
    assert walk[-1] == 36
    assert walks.counts.max() > 0
    other = JoinMotions(joins.vertices, joins.lengths, np.ones((w, 2), dtype=bool))
    assert not other.same_as(joins)
    search.union_walk(other, 0)
    assert len(made) == 2
    search.forget_trees()
    search.union_walk(other, 0)
    assert len(made) == 3


def _libraries(
    monkeypatch: pytest.MonkeyPatch,
    radius: float | tuple[float, ...],
    graph: ExplicitGraph,
    x: np.ndarray,
    follow: bool = True,
) -> list[list[tuple[int, ...]]]:
    """Every query's library with the first search radius ``radius`` (a fresh search per radius), ``follow``: the
    union's paths read where they are a world's only shortest ones."""
    monkeypatch.setattr(goal_trees, "ELLIPSE_FACTORS", radius if isinstance(radius, tuple) else (radius,))
    monkeypatch.setattr(goal_trees, "FOLLOW_UNION", follow)
    search = SearchWorlds(GraphArcs(graph), graph.lengths, x, seed=1)
    rng = np.random.default_rng(9)
    out = []
    for _ in range(12):
        goal = int(rng.integers(36))
        for _ in range(3):  # replans to the same goal: the kept tree widened where a start is not covered
            start = int(rng.integers(36))
            if start != goal:
                out.append([tuple(p.tolist()) for p in library_paths(search, start, goal, max_paths=500)])
            vertices = rng.choice(36, size=3, replace=False)
            joins = Joins(vertices, rng.uniform(0.2, 3.0, 3), np.arange(3) + 999, rng.random((x.shape[0], 3)) < 0.7)
            out.append([tuple(p.tolist()) for p in library_paths(search, joins, goal, max_paths=500)])
        # An off-graph goal (searched anew each time), from a vertex and from an off-graph start.
        into = rng.choice(36, size=4, replace=False)
        goal_joins = Joins(into, rng.uniform(0.2, 3.0, 4), np.arange(4) + 2000, rng.random((x.shape[0], 4)) < 0.7)
        for origin in (int(rng.integers(36)), joins):
            out.append([tuple(p.tolist()) for p in library_paths(search, origin, goal_joins, max_paths=500)])
    return out


@pytest.mark.parametrize("directed", [False, True])
def test_searching_only_as_far_as_the_start_gives_the_paths_of_whole_trees(
    monkeypatch: pytest.MonkeyPatch, directed: bool
) -> None:
    graph, x = _grid(directed)
    whole = _libraries(monkeypatch, np.inf, graph, x, follow=False)
    assert sum(len(paths) for paths in whole) > 100
    for radius in (0.5, 1.0, 1.25, 2.0, (1.25, 2.5, 5.0)):  # below 1 nothing is found in the ellipse
        assert _libraries(monkeypatch, radius, graph, x, follow=False) == whole
        assert _libraries(monkeypatch, radius, graph, x) == whole


@pytest.mark.parametrize("directed", [False, True])
def test_reading_the_unions_paths_gives_the_paths_of_searched_worlds_where_lengths_tie(
    monkeypatch: pytest.MonkeyPatch, directed: bool
) -> None:
    graph, x = _grid(directed)
    # Equal lengths: many equally short paths, so the union's path is often not a world's only shortest one.
    tied = ExplicitGraph(graph.edges, np.ones(graph.num_edges), graph.num_vertices, directed)
    whole = _libraries(monkeypatch, np.inf, tied, x, follow=False)
    assert _libraries(monkeypatch, 1.25, tied, x) == whole


def _reference_walks(graph: ExplicitGraph, x: np.ndarray, goal: int, start: int) -> list[tuple[int, ...] | None]:
    """Each search world's walk from ``start`` read off whole trees (every world searched without bound)."""
    search = SearchWorlds(GraphArcs(graph), graph.lengths, x, seed=1)
    walks = search.tree(goal).walks(np.full(search.num_worlds, start))
    return [None if w is None else tuple(w.tolist()) for w in walks]


def _walks(search: SearchWorlds, goal: int, start: int) -> list[tuple[int, ...] | None]:
    walks = search.walks_from(goal, start)
    return [tuple(walks.table[w, :n].tolist()) if n else None for w, n in enumerate(walks.counts.tolist())]


def test_a_bounded_tree_searches_only_what_the_start_needs_and_is_widened_in_place(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    graph, x = _grid(False)
    monkeypatch.setattr(goal_trees, "ELLIPSE_FACTORS", (2.0,))  # so that the detours near the start stay bounded
    search = SearchWorlds(GraphArcs(graph), graph.lengths, x, seed=1)
    tree = search.tree(35, 28)  # a start two rows from the goal: a small part of the grid searched
    searched = tree.rows.searched
    # Worlds where the union's path is the only shortest one were not searched at all.
    assert 0 < searched.sum() < search.num_worlds
    assert _walks(search, 35, 28) == _reference_walks(graph, x, 35, 28)
    radius = tree.world_radius()
    bounded = searched & np.isfinite(radius)
    assert bounded.any()  # searched only as far as the start needed
    assert not np.isfinite(tree.dist_at(np.array([0]))[bounded, 0]).any()  # the far corner lies beyond them
    assert search.tree(35, 0) is tree  # searched further in place for the far start
    assert _walks(search, 35, 0) == _reference_walks(graph, x, 35, 0)
    reference = SearchWorlds(GraphArcs(graph), graph.lengths, x, seed=1).tree(35)
    whole = np.isinf(tree.world_radius())
    every = np.arange(36)
    assert np.array_equal(tree.dist_at(every)[whole], reference.dist_at(every)[whole])
    for vertex in every.tolist():
        hops = tree.rows.hop_of(np.flatnonzero(whole), np.full(int(whole.sum()), vertex))
        assert np.array_equal(hops, reference.rows.hop_of(np.flatnonzero(whole), np.full(int(whole.sum()), vertex)))
    # A world whose start is walled off from the goal (another part of its free arcs) is never searched for it.
    assert tree.parts is not None
    walled = tree.parts[:, 0] != tree.parts[:, 35]
    assert walled.any()
    assert not np.isfinite(reference.dist_at(np.array([0]))[walled, 0]).any()
