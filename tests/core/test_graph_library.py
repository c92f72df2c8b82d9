"""Graph and library model: lookups, incidence and path validity against brute force."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.library import PathLibrary
from drd_planner.core.problem import Problem
from drd_planner.core.worlds import WorldDatabase
from drd_planner.exceptions import ProblemError


def test_undirected_lookup_and_vertex_paths() -> None:
    g = ExplicitGraph(np.array([[0, 1], [2, 1], [2, 3]]), np.array([1.0, 2.0, 3.0]), 4)
    assert g.edge_id(1, 0) == 0
    assert g.edge_id(1, 2) == 1
    np.testing.assert_array_equal(g.vertex_path_to_edges([0, 1, 2, 3]), [0, 1, 2])
    with pytest.raises(ProblemError, match="no edge"):
        g.edge_id(0, 3)


def test_directed_graph_refuses_reverse_traversal_and_duplicates() -> None:
    g = ExplicitGraph(np.array([[0, 1]]), np.array([1.0]), 2, directed=True)
    with pytest.raises(ProblemError):
        g.edge_id(1, 0)
    with pytest.raises(ProblemError, match="duplicate"):
        ExplicitGraph(np.array([[0, 1], [1, 0]]), np.array([1.0, 1.0]), 2)
    with pytest.raises(ProblemError):
        ExplicitGraph(np.array([[0, 5]]), np.array([1.0]), 2)
    with pytest.raises(ProblemError):
        ExplicitGraph(np.array([[0, 1]]), np.array([np.nan]), 2)


def test_library_incidence_and_validity_match_brute_force() -> None:
    rng = np.random.default_rng(0)
    paths = [rng.choice(12, size=int(rng.integers(1, 6)), replace=False) for _ in range(20)]
    lib = PathLibrary(tuple(paths), 12)
    dense = lib.dense_incidence()
    for i, p in enumerate(paths):
        assert set(np.flatnonzero(dense[i])) == set(p.tolist())
    for e in range(12):
        assert set(lib.paths_through(e).tolist()) == {i for i, p in enumerate(paths) if e in p}
    X = rng.random((30, 12)) < 0.8
    brute = np.array([[all(x[e] for e in p) for p in paths] for x in X])
    np.testing.assert_array_equal(lib.valid_paths(X), brute)
    np.testing.assert_array_equal(lib.valid_paths(X[0]), brute[0])
    np.testing.assert_array_equal(lib.library_edges, np.unique(np.concatenate(paths)))
    np.testing.assert_allclose(lib.path_costs(np.arange(12.0)), [float(np.sum(p)) for p in paths])


def test_library_refuses_bad_paths() -> None:
    with pytest.raises(ProblemError, match="twice"):
        PathLibrary.from_sequences([[0, 0]], 2)
    with pytest.raises(ProblemError, match="outside"):
        PathLibrary.from_sequences([[3]], 2)
    with pytest.raises(ProblemError, match="no edges"):
        PathLibrary.from_sequences([[]], 2)


def test_problem_and_worlds_validate_shapes() -> None:
    lib = PathLibrary.from_sequences([[0], [1]], 2)
    X = np.array([[True, False], [False, True]])
    worlds = WorldDatabase(X, lib.valid_paths(X), np.array([0]), np.array([1]))
    problem = Problem("p", lib, np.ones(2), worlds=worlds)
    assert problem.require_worlds() is worlds
    with pytest.raises(ProblemError, match="positive"):
        Problem("p", lib, np.array([1.0, 0.0]))
    with pytest.raises(ProblemError, match="overlap"):
        WorldDatabase(X, lib.valid_paths(X), np.array([0, 1]), np.array([1]))
    with pytest.raises(ProblemError, match="no world database"):
        Problem("p", lib, np.ones(2)).require_worlds()


def test_the_incidences_are_the_sorted_path_by_edge_matrix_in_both_orders() -> None:
    rng = np.random.default_rng(4)
    for _ in range(50):
        num_edges = int(rng.integers(5, 200))
        paths = tuple(
            rng.choice(num_edges, size=int(rng.integers(1, min(num_edges, 12) + 1)), replace=False)
            for _ in range(int(rng.integers(1, 30)))
        )
        library = PathLibrary(paths, num_edges)
        dense = np.zeros((len(paths), num_edges))
        for i, p in enumerate(paths):
            dense[i, p] = 1.0
        for matrix in (library.incidence, library.incidence_csc):
            assert matrix.has_sorted_indices
            assert np.array_equal(matrix.toarray(), dense)
        assert library.incidence.indptr.tolist() == np.concatenate([[0], np.cumsum([p.size for p in paths])]).tolist()
        assert library.library_edges.tolist() == np.unique(np.concatenate(paths)).tolist()
