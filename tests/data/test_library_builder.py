"""Tests of the path-library builder (per-world Yen k-shortest paths, union, subsample) and the split."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse import coo_array
from scipy.sparse.csgraph import dijkstra

from drd_planner.core.graph import ExplicitGraph
from drd_planner.data.library_builder import build_path_library, k_shortest_paths_union, split_worlds
from drd_planner.domains.planar import edge_free_matrix, random_geometric_graph, sample_worlds
from drd_planner.exceptions import ProblemError

# Ladder graph: start S=0, goal T=5, rungs a1..a4 = 1..4 with S-ai of length i and ai-T of length 1,
# plus a cross edge a1-a2 of length 0.25. Its loopless S-T paths and lengths:
#   S-a1-T 2, S-a1-a2-T 2.25, S-a2-T 3, S-a2-a1-T 3.25, S-a3-T 4, S-a4-T 5.
S, T = 0, 5
LADDER_EDGES = [(0, 1), (0, 2), (0, 3), (0, 4), (1, 5), (2, 5), (3, 5), (4, 5), (1, 2)]
LADDER_LENGTHS = [1.0, 2.0, 3.0, 4.0, 1.0, 1.0, 1.0, 1.0, 0.25]
ALL_PATHS_BY_LENGTH = [(0, 1, 5), (0, 1, 2, 5), (0, 2, 5), (0, 2, 1, 5), (0, 3, 5), (0, 4, 5)]
CROSS = 8  # edge id of a1-a2
S_A1 = 0  # edge id of S-a1


def ladder() -> ExplicitGraph:
    """The hand-made ladder graph above."""
    return ExplicitGraph(np.array(LADDER_EDGES), np.array(LADDER_LENGTHS), 6)


def vertex_paths(lib_vertex_paths: tuple[np.ndarray, ...] | None) -> set[tuple[int, ...]]:
    """A library's vertex paths as a set of tuples."""
    assert lib_vertex_paths is not None
    return {tuple(int(v) for v in p) for p in lib_vertex_paths}


def test_k_shortest_per_world_on_hand_made_graph() -> None:
    g = ladder()
    all_free = np.ones((1, g.num_edges), dtype=bool)
    lib = build_path_library(g, all_free, S, T, k=5, seed=0)
    assert vertex_paths(lib.vertex_paths) == set(ALL_PATHS_BY_LENGTH[:5])  # S-a4-T (length 5) is 6th
    lib2 = build_path_library(g, all_free, S, T, k=2, seed=0)
    assert vertex_paths(lib2.vertex_paths) == {(0, 1, 5), (0, 1, 2, 5)}
    no_cross = all_free.copy()
    no_cross[0, CROSS] = False
    lib3 = build_path_library(g, no_cross, S, T, k=5, seed=0)
    assert vertex_paths(lib3.vertex_paths) == {(0, 1, 5), (0, 2, 5), (0, 3, 5), (0, 4, 5)}


def test_union_over_worlds_dedup_and_unsolvable_world() -> None:
    g = ladder()
    x = np.ones((4, g.num_edges), dtype=bool)
    x[1, S_A1] = False  # world 1: S-a2-T 3, S-a2-a1-T 3.25, S-a3-T 4, S-a4-T 5
    x[2, :4] = False  # world 2: start isolated, no path
    # world 3 equals world 0 (duplicates must not repeat paths)
    union = k_shortest_paths_union(g, x, S, T, k=5)
    assert {v for _, v in union} == set(ALL_PATHS_BY_LENGTH)
    assert len(union) == len(ALL_PATHS_BY_LENGTH)
    keys = [e for e, _ in union]
    assert keys == sorted(keys)
    lib = build_path_library(g, x, S, T, k=5, seed=0)
    assert lib.num_paths == 6
    assert [tuple(p.tolist()) for p in lib.path_edges] == keys
    r = lib.valid_paths(x)
    assert not r[2].any()
    assert r.any(axis=0).all()


def test_directed_graph_follows_edge_orientation() -> None:
    # 0 -> 1 -> 2 is the only directed path; 0 -> 3 <- 2 would be a path if the graph were undirected.
    edges = np.array([[0, 1], [1, 2], [0, 3], [2, 3]])
    lengths = np.array([5.0, 5.0, 1.0, 1.0])
    x = np.ones((1, 4), dtype=bool)
    directed = ExplicitGraph(edges, lengths, 4, directed=True)
    assert vertex_paths(build_path_library(directed, x, 0, 2, seed=0).vertex_paths) == {(0, 1, 2)}
    undirected = ExplicitGraph(edges, lengths, 4, directed=False)
    lib = build_path_library(undirected, x, 0, 2, seed=0)
    assert vertex_paths(lib.vertex_paths) == {(0, 1, 2), (0, 3, 2)}
    # vertex paths and edge paths agree even when an undirected edge is walked against its orientation
    for ep, vp in zip(lib.path_edges, lib.vertex_paths or (), strict=True):
        assert np.array_equal(undirected.vertex_path_to_edges(vp), ep)


def test_empty_union_raises() -> None:
    g = ladder()
    x = np.ones((3, g.num_edges), dtype=bool)
    x[:, 4:8] = False  # goal isolated in every world
    with pytest.raises(ProblemError, match="no world has a collision-free path"):
        build_path_library(g, x, S, T, seed=0)


def test_bad_inputs_raise() -> None:
    g = ladder()
    with pytest.raises(ProblemError, match="shape"):
        build_path_library(g, np.ones((2, 3), dtype=bool), S, T, seed=0)
    with pytest.raises(ProblemError, match="same vertex"):
        build_path_library(g, np.ones((1, g.num_edges), dtype=bool), S, S, seed=0)
    with pytest.raises(ProblemError, match="max_paths"):
        build_path_library(g, np.ones((1, g.num_edges), dtype=bool), S, T, max_paths=0, seed=0)


def test_subsample_is_seeded_uniform_subset_in_order() -> None:
    g = ladder()
    x = np.ones((2, g.num_edges), dtype=bool)
    x[1, S_A1] = False
    full = [tuple(p.tolist()) for p in build_path_library(g, x, S, T, seed=0).path_edges]
    assert len(full) == 6
    subsets = set()
    for seed in range(12):
        lib = build_path_library(g, x, S, T, max_paths=3, seed=seed)
        kept = [tuple(p.tolist()) for p in lib.path_edges]
        assert len(kept) == 3
        assert set(kept) <= set(full)
        assert kept == sorted(kept)
        again = build_path_library(g, x, S, T, max_paths=3, seed=seed)
        assert [tuple(p.tolist()) for p in again.path_edges] == kept
        subsets.add(tuple(kept))
    assert len(subsets) > 1  # the seed matters


@pytest.fixture(scope="module")
def planar_case() -> tuple[ExplicitGraph, int, int, np.ndarray]:
    """A small RGG with one-wall worlds: (graph, start, goal, X)."""
    g, s, t = random_geometric_graph(70, seed=5)
    assert g.vertex_states is not None
    boxes = sample_worlds("one_wall", 40, seed=11, keep_clear=g.vertex_states[[s, t]])
    return g, s, t, edge_free_matrix(g, boxes)


def test_planar_library_paths_are_valid_start_goal_paths(
    planar_case: tuple[ExplicitGraph, int, int, np.ndarray],
) -> None:
    g, s, t, x = planar_case
    lib = build_path_library(g, x, s, t, k=5, max_paths=40, seed=2)
    assert lib.vertex_paths is not None
    assert lib.num_paths == 40
    for ep, vp in zip(lib.path_edges, lib.vertex_paths, strict=True):
        assert vp[0] == s
        assert vp[-1] == t
        assert np.unique(vp).size == vp.size  # loopless
        assert np.array_equal(g.vertex_path_to_edges(vp), ep)  # every step is a graph edge
    r = lib.valid_paths(x)
    assert r.any(axis=0).all()  # each path was a shortest path on some world's free edges


def test_planar_library_has_each_worlds_shortest_path_when_not_subsampled(
    planar_case: tuple[ExplicitGraph, int, int, np.ndarray],
) -> None:
    g, s, t, x = planar_case
    lib = build_path_library(g, x, s, t, k=1, max_paths=10_000, seed=0)
    r = lib.valid_paths(x)
    lengths = np.array([g.lengths[p].sum() for p in lib.path_edges])
    solvable = 0
    for h in range(x.shape[0]):
        # brute force: scipy's Dijkstra on world h's free edges
        free = x[h]
        e = g.edges[free]
        adj = coo_array((g.lengths[free], (e[:, 0], e[:, 1])), shape=(g.num_vertices, g.num_vertices))
        best = dijkstra(adj, directed=False, indices=s)[t]
        if np.isinf(best):
            assert not r[h].any()
        else:
            solvable += 1
            assert np.isclose(lengths[r[h]].min(), best)
    assert 0 < solvable < x.shape[0]


def test_determinism_same_seed_same_library(planar_case: tuple[ExplicitGraph, int, int, np.ndarray]) -> None:
    g, s, t, x = planar_case
    a = build_path_library(g, x, s, t, max_paths=30, seed=4)
    b = build_path_library(g, x, s, t, max_paths=30, seed=4)
    c = build_path_library(g, x, s, t, max_paths=30, seed=5)
    ta = [tuple(p.tolist()) for p in a.path_edges]
    assert ta == [tuple(p.tolist()) for p in b.path_edges]
    assert ta != [tuple(p.tolist()) for p in c.path_edges]


def test_split_worlds_properties() -> None:
    rng = np.random.default_rng(0)
    r = rng.random((200, 15)) < 0.05  # about half the worlds have no valid path
    eligible = set(np.flatnonzero(r.any(axis=1)).tolist())
    assert 20 < len(eligible) < 200
    train, test = split_worlds(r, test_fraction=0.1, seed=3)
    assert test.size == 20
    assert set(test.tolist()) <= eligible
    assert np.intersect1d(train, test).size == 0
    assert np.array_equal(np.union1d(train, test), np.arange(200))
    assert np.array_equal(train, np.sort(train))
    assert np.array_equal(test, np.sort(test))
    assert train.dtype == np.int64
    assert test.dtype == np.int64
    train2, test2 = split_worlds(r, test_fraction=0.1, seed=3)
    assert np.array_equal(test, test2)
    assert np.array_equal(train, train2)
    tests = {tuple(split_worlds(r, test_fraction=0.1, seed=s)[1].tolist()) for s in range(5)}
    assert len(tests) > 1


def test_split_worlds_with_few_solvable_worlds() -> None:
    r = np.zeros((50, 4), dtype=bool)
    r[[3, 17, 40], 1] = True
    train, test = split_worlds(r, test_fraction=0.2, seed=0)
    assert test.tolist() == [3, 17, 40]  # fewer than round(0.2 * 50) = 10 eligible: all of them
    assert train.size == 47
    train, test = split_worlds(np.zeros((5, 2), dtype=bool), seed=0)
    assert test.size == 0
    assert train.tolist() == [0, 1, 2, 3, 4]
    with pytest.raises(ProblemError):
        split_worlds(r, test_fraction=1.5, seed=0)
