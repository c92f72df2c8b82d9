"""The online path library: each searched world's shortest free path, deterministic, bounded."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from drd_planner.core.lazysp import GraphArcs
from drd_planner.data.planar_problem import make_planar_problem
from drd_planner.exceptions import ProblemError
from drd_planner.planner.query_library import build_query_library, query_library


@pytest.fixture(scope="module")
def setup() -> tuple[object, np.ndarray]:
    problem = make_planar_problem(model="forest", num_worlds=120, seed=4)
    worlds = problem.require_worlds()
    return problem, worlds.X[worlds.train_ids]


def _shortest_length(graph: object, row: np.ndarray, s: int, g: int) -> float | None:
    nxg = nx.Graph()
    for e in np.flatnonzero(row).tolist():
        u, v = graph.edges[e]  # type: ignore[attr-defined]
        nxg.add_edge(int(u), int(v), weight=float(graph.lengths[e]))  # type: ignore[attr-defined]
    try:
        return float(nx.shortest_path_length(nxg, s, g, weight="weight"))
    except (nx.NetworkXNoPath, nx.NodeNotFound):
        return None


def test_paths_are_free_shortest_paths_and_cover_every_connected_world(
    setup: tuple[object, np.ndarray],
) -> None:
    problem, X = setup
    graph = problem.graph  # type: ignore[attr-defined]
    s, g = 2, 37
    paths = build_query_library(
        GraphArcs(graph), graph.lengths, X, s, g, max_paths=500, seed=0, max_searches=10**6
    )
    assert paths
    lengths = [float(graph.lengths[p].sum()) for p in paths]
    for p in paths:
        valid = X[:, p].all(axis=1)
        assert valid.any()  # each path is free in some training world
    for h in range(X.shape[0]):
        best = _shortest_length(graph, X[h], s, g)
        free = [lengths[k] for k, p in enumerate(paths) if X[h, p].all()]
        if best is None:
            assert not free
        else:  # with unlimited searches, every world's own shortest length is in the library
            assert min(free) == pytest.approx(best)


def test_search_budget_bounds_the_library(setup: tuple[object, np.ndarray]) -> None:
    problem, X = setup
    graph = problem.graph  # type: ignore[attr-defined]
    arcs = GraphArcs(graph)
    small = build_query_library(arcs, graph.lengths, X, 2, 37, max_paths=500, seed=0, max_searches=3)
    full = build_query_library(arcs, graph.lengths, X, 2, 37, max_paths=500, seed=0, max_searches=10**6)
    assert 1 <= len(small) <= 3 < len(full)
    as_tuples = {tuple(p.tolist()) for p in full}
    assert all(tuple(p.tolist()) in as_tuples for p in small)  # the same worlds' paths


def test_deterministic_and_bounded(setup: tuple[object, np.ndarray]) -> None:
    problem, X = setup
    graph = problem.graph  # type: ignore[attr-defined]
    arcs = GraphArcs(graph)
    a = query_library(arcs, graph.edges, graph.lengths, X, 0, 40, max_paths=5, seed=3)
    b = query_library(arcs, graph.edges, graph.lengths, X, 0, 40, max_paths=5, seed=3)
    assert a is not None and b is not None
    assert a.num_paths <= 5
    assert all(np.array_equal(x, y) for x, y in zip(a.path_edges, b.path_edges, strict=True))
    assert a.vertex_paths is not None
    for vp in a.vertex_paths:
        assert vp[0] == 0 and vp[-1] == 40


def test_no_connecting_world_gives_no_library(setup: tuple[object, np.ndarray]) -> None:
    problem, X = setup
    graph = problem.graph  # type: ignore[attr-defined]
    none_free = np.zeros_like(X)
    assert (
        query_library(GraphArcs(graph), graph.edges, graph.lengths, none_free, 0, 40, max_paths=5, seed=0)
        is None
    )
    with pytest.raises(ProblemError, match="same vertex"):
        build_query_library(GraphArcs(graph), graph.lengths, X, 3, 3, max_paths=5, seed=0)
