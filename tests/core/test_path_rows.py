"""Tests of the padded path table: each column is one path's edges in order, padded with the neutral slot."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.core.library import PathLibrary
from drd_planner.core.path_rows import PathRows, column_sums, library_rows


def _random_library(seed: int, num_edges: int = 30, num_paths: int = 12) -> PathLibrary:
    rng = np.random.default_rng(seed)
    paths = [rng.choice(num_edges, size=int(rng.integers(1, 9)), replace=False) for _ in range(num_paths)]
    return PathLibrary(tuple(paths), num_edges)


def test_each_column_holds_its_paths_edges_in_order_then_the_pad() -> None:
    library = _random_library(0)
    csr = library.incidence
    rows = PathRows(csr.indptr, csr.indices, library.num_edges)
    used = np.unique(np.concatenate(library.path_edges))
    assert rows.edges.tolist() == used.tolist()
    assert rows.pad == used.size
    assert rows.column[used].tolist() == list(range(used.size))
    assert set(rows.column[np.setdiff1d(np.arange(library.num_edges), used)].tolist()) <= {rows.pad}
    assert rows.table.shape == (max(p.size for p in library.path_edges), library.num_paths)
    for i in range(library.num_paths):
        row = csr.indices[csr.indptr[i] : csr.indptr[i + 1]]  # the incidence's order (sorted edge ids)
        column = rows.table[:, i]
        assert rows.edges[column[: row.size]].tolist() == row.tolist()
        assert (column[row.size :] == rows.pad).all()


def test_edge_counts_count_the_paths_through_each_library_edge() -> None:
    library = _random_library(1)
    rows = library_rows(library)
    rng = np.random.default_rng(2)
    for _ in range(5):
        paths = np.flatnonzero(rng.random(library.num_paths) < 0.5)
        expected = np.zeros(rows.pad, dtype=np.int64)
        for i in paths.tolist():
            expected[rows.column[library.path_edges[i]]] += 1
        assert rows.edge_counts(paths).tolist() == expected.tolist()
    assert rows.edge_counts(np.zeros(0, dtype=np.int64)).tolist() == [0] * rows.pad


def test_a_librarys_table_is_built_once() -> None:
    library, other = _random_library(3), _random_library(4)
    assert library_rows(library) is library_rows(library)
    assert library_rows(other) is not library_rows(library)
    assert library_rows(other).table.shape[1] == other.num_paths


@pytest.mark.parametrize("rows", [1, 2, 8, 9, 14, 33])
@pytest.mark.parametrize("columns", [1, 2, 3, 500])
def test_column_sums_add_term_after_term_as_the_running_sums_do(rows: int, columns: int) -> None:
    rng = np.random.default_rng(rows * 1000 + columns)
    block = np.log(rng.random((rows, columns))) * rng.random((rows, columns))
    block[rng.random((rows, columns)) < 0.3] = 0.0  # the pad slots and checked edges add 0
    got = column_sums(block)
    assert got.tolist() == block.cumsum(axis=0)[-1].tolist()  # bit for bit
    one_by_one = block[0].tolist()
    for row in block[1:].tolist():
        one_by_one = [a + b for a, b in zip(one_by_one, row, strict=True)]
    assert got.tolist() == one_by_one
