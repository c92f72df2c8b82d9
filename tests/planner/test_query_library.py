"""The online path library: each search world's shortest free path (from the goal's trees), deterministic."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from drd_planner.core.lazysp import GraphArcs
from drd_planner.data.planar_problem import make_planar_problem
from drd_planner.exceptions import ProblemError
from drd_planner.planner.goal_trees import SearchWorlds
from drd_planner.planner.query_graph import Joins
from drd_planner.planner.query_library import library_paths, query_library


@pytest.fixture(scope="module")
def setup() -> tuple[object, np.ndarray]:
    problem = make_planar_problem(model="forest", num_worlds=120, seed=4)
    worlds = problem.require_worlds()
    return problem, worlds.X[worlds.train_ids]


def _search(problem: object, X: np.ndarray, count: int = 10**6, seed: int = 0) -> SearchWorlds:
    graph = problem.graph  # type: ignore[attr-defined]
    return SearchWorlds(GraphArcs(graph), graph.lengths, X, seed=seed, count=count)


def _shortest_length(graph: object, row: np.ndarray, s: int, g: int) -> float | None:
    nxg = nx.Graph()
    for e in np.flatnonzero(row).tolist():
        u, v = graph.edges[e]  # type: ignore[attr-defined]
        nxg.add_edge(int(u), int(v), weight=float(graph.lengths[e]))  # type: ignore[attr-defined]
    try:
        return float(nx.shortest_path_length(nxg, s, g, weight="weight"))
    except (nx.NetworkXNoPath, nx.NodeNotFound):
        return None


def test_paths_are_free_shortest_paths_and_cover_every_searched_world(
    setup: tuple[object, np.ndarray],
) -> None:
    problem, X = setup
    graph = problem.graph  # type: ignore[attr-defined]
    s, g = 2, 37
    search = _search(problem, X)
    paths = library_paths(search, s, g, max_paths=500)
    assert paths
    lengths = [float(graph.lengths[p].sum()) for p in paths]
    for p in paths:
        assert X[:, p].all(axis=1).any()  # each path is free in some training world
    for h in search.worlds.tolist():
        best = _shortest_length(graph, X[h], s, g)
        free = [lengths[k] for k, p in enumerate(paths) if X[h, p].all()]
        if best is None:
            assert not free
        else:  # every searched world's own shortest length is in the library
            assert min(free) == pytest.approx(best)


def test_fewer_search_worlds_give_a_subset_of_the_paths(setup: tuple[object, np.ndarray]) -> None:
    problem, X = setup
    small = library_paths(_search(problem, X, count=3), 2, 37, max_paths=500)
    full = library_paths(_search(problem, X), 2, 37, max_paths=500)
    assert 1 <= len(small) <= 3 < len(full)
    as_tuples = {tuple(p.tolist()) for p in full}
    assert all(tuple(p.tolist()) in as_tuples for p in small)  # the same worlds come first in the order


def test_deterministic_and_bounded(setup: tuple[object, np.ndarray]) -> None:
    problem, X = setup
    graph = problem.graph  # type: ignore[attr-defined]
    a = query_library(_search(problem, X, seed=3), graph.edges, 0, 40, start_vertex=0, max_paths=5)
    b = query_library(_search(problem, X, seed=3), graph.edges, 0, 40, start_vertex=0, max_paths=5)
    assert a is not None
    assert b is not None
    assert a.num_paths <= 5
    assert all(np.array_equal(x, y) for x, y in zip(a.path_edges, b.path_edges, strict=True))
    assert a.vertex_paths is not None
    for vp in a.vertex_paths:
        assert vp[0] == 0
        assert vp[-1] == 40


def test_joined_start_and_goal_take_the_best_free_join(setup: tuple[object, np.ndarray]) -> None:
    problem, X = setup
    graph = problem.graph  # type: ignore[attr-defined]
    search = _search(problem, X)
    e, n = graph.num_edges, X.shape[0]
    # A start joined to vertices 2 and 5, a goal joined from 37 and 40; joins to 2 and into 37 never free.
    start = Joins(np.array([2, 5]), np.array([1.0, 9.0]), np.array([e, e + 1]), np.tile([False, True], (n, 1)))
    goal = Joins(np.array([37, 40]), np.array([1.0, 1.0]), np.array([e + 2, e + 3]), np.tile([False, True], (n, 1)))
    paths = library_paths(search, start, goal, max_paths=500)
    assert paths
    for p in paths:
        # the only free joins
        assert p[0] == e + 1
        assert p[-1] == e + 3
        inner = p[1:-1]
        assert X[:, inner].all(axis=1).any()
        length = float(graph.lengths[inner].sum())
        # some search world's shortest free path from the join's vertex to the goal's
        worlds = [h for h in search.worlds.tolist() if X[h, inner].all()]
        assert any(_shortest_length(graph, X[h], 5, 40) == pytest.approx(length) for h in worlds)


def test_no_connecting_world_gives_no_library(setup: tuple[object, np.ndarray]) -> None:
    problem, X = setup
    graph = problem.graph  # type: ignore[attr-defined]
    none_free = np.zeros_like(X)
    none = _search(problem, none_free)
    assert query_library(none, graph.edges, 0, 40, start_vertex=0, max_paths=5) is None
    with pytest.raises(ProblemError, match="same vertex"):
        library_paths(_search(problem, X), 3, 3, max_paths=5)


def test_a_goal_with_more_joins_than_spare_arcs_searches_through_the_first(
    setup: tuple[object, np.ndarray],
) -> None:
    problem, X = setup
    graph = problem.graph  # type: ignore[attr-defined]
    search = _search(problem, X)
    k = search.slots + 5
    vertices = np.arange(k, dtype=np.int64)
    goal = Joins(vertices, np.ones(k), graph.num_edges + vertices, np.ones((X.shape[0], k), dtype=bool))
    paths = library_paths(search, 40 if 40 >= k else k + 1, goal, max_paths=50)
    assert paths
    assert all(int(p[-1]) < graph.num_edges + search.slots for p in paths)
