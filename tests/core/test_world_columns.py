"""Packed world columns: free counts over any subset of worlds equal the plain sums."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drd_planner.core.world_columns import WorldColumns, pack_rows
from drd_planner.exceptions import ProblemError


@settings(max_examples=40, deadline=None)
@given(n=st.integers(1, 200), e=st.integers(1, 30), seed=st.integers(0, 2**31))
def test_counts_equal_the_sums_over_the_rows(n: int, e: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    x = rng.random((n, e)) < 0.6
    columns = WorldColumns(x)
    for _ in range(3):
        rows = rng.random(n) < rng.random()
        assert np.array_equal(columns.free_counts(rows), x[rows].sum(axis=0))
    assert np.array_equal(columns.free_totals, x.sum(axis=0))
    every = columns.free_counts(np.ones(n, dtype=bool))  # every world: the kept totals, as a copy
    assert np.array_equal(every, x.sum(axis=0))
    every[:] = -1
    assert np.array_equal(columns.free_totals, x.sum(axis=0))
    assert columns.num_worlds == n
    assert columns.num_edges == e
    edges = rng.integers(0, e, size=7)  # repeats allowed
    assert np.array_equal(columns.rows_of(edges), x[:, edges].T)


def test_rows_are_packed_little_endian_in_64_bit_words() -> None:
    rows = np.zeros(70, dtype=bool)
    rows[[0, 63, 64, 69]] = True
    words = pack_rows(rows)
    assert words.dtype == np.uint64
    assert words.size == 2
    assert int(words[0]) == (1 << 0) | (1 << 63)
    assert int(words[1]) == (1 << 0) | (1 << 5)


def test_a_mask_of_another_size_is_refused() -> None:
    columns = WorldColumns(np.ones((70, 3), dtype=bool))
    with pytest.raises(ProblemError, match="70 worlds"):
        columns.free_counts(np.ones(200, dtype=bool))


@settings(max_examples=40, deadline=None)
@given(n=st.integers(1, 150), e=st.integers(1, 12), p=st.integers(1, 11), seed=st.integers(0, 2**31))
def test_at_least_marks_the_worlds_where_enough_of_a_rows_edges_are_free(n: int, e: int, p: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    x = rng.random((n, e)) < rng.random()
    columns = WorldColumns(x)
    edges = rng.integers(0, e, size=(9, p))  # repeats count once per occurrence
    counts = x[:, edges].sum(axis=2).T  # (9, n)
    for needed in (-1, 0, 1, (p + 1) // 2, p, p + 1):
        words = columns.at_least(edges, needed)
        assert words.shape == (9, columns.bits.shape[1])
        unpacked = np.unpackbits(words.view(np.uint8), axis=1, bitorder="little")
        assert np.array_equal(unpacked[:, :n].astype(bool), counts >= needed)
        assert not unpacked[:, n:].any()  # padding stays 0
    with pytest.raises(ProblemError, match=r"\(M, P\)"):
        columns.at_least(edges.ravel(), 1)
