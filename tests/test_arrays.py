"""The distinct rows of a matrix: the same answer as ``np.unique(axis=0)``, from packed bytes."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.arrays import first_distinct_rows, row_groups, unique_bool_rows


@pytest.mark.parametrize("shape", [(900, 500), (40, 3), (12, 9), (7, 1), (1, 17), (0, 4), (5, 0)])
def test_unique_bool_rows_is_numpys_unique_over_rows(shape: tuple[int, int]) -> None:
    rng = np.random.default_rng(shape[0] + shape[1])
    rows = rng.random(shape) < 0.3
    if shape[0] > 4:
        rows[4] = rows[0]  # a repeated row
    distinct, inverse = unique_bool_rows(rows)
    expected, expected_inverse = np.unique(rows, axis=0, return_inverse=True)
    assert distinct.dtype == bool
    assert inverse.dtype == np.int64
    assert np.array_equal(distinct, expected)
    assert np.array_equal(inverse, np.asarray(expected_inverse).ravel())
    assert np.array_equal(distinct[inverse], rows)


@pytest.mark.parametrize("dtype", [np.int32, np.int64, np.bool_])
def test_first_distinct_rows_are_numpys_first_indices(dtype: type) -> None:
    rng = np.random.default_rng(3)
    rows = rng.integers(0, 3, size=(60, 5)).astype(dtype)
    first = first_distinct_rows(rows[:, ::2])  # a non-contiguous view too
    _, expected = np.unique(rows[:, ::2], axis=0, return_index=True)
    assert first.tolist() == np.sort(expected).tolist()
    assert first_distinct_rows(np.zeros((0, 3))).size == 0
    assert first_distinct_rows(np.zeros((4, 0))).tolist() == [0]


def test_a_matrix_is_required() -> None:
    with pytest.raises(ValueError, match="matrix"):
        unique_bool_rows(np.zeros(3, dtype=bool))
    with pytest.raises(ValueError, match="matrix"):
        row_groups(np.zeros(3))


def test_distinct_bool_rows_are_found_exactly() -> None:
    """Bool rows (the training worlds) are compared on their packed bits, never merged when they differ."""
    rng = np.random.default_rng(0)
    base = rng.random((30, 100)) < 0.5
    rows = base[rng.integers(0, 30, size=200)]
    _, reference = np.unique(rows, axis=0, return_index=True)
    assert first_distinct_rows(rows).tolist() == np.sort(reference).tolist()
    close = np.zeros((3, 9), dtype=bool)
    close[1, 8] = True  # differs from row 0 only in the last bit, past the first byte
    assert first_distinct_rows(close).tolist() == [0, 1]


def test_row_groups_number_the_groups_in_order_of_their_first_row() -> None:
    rows = np.array([[2, 1], [0, 0], [2, 1], [1, 5], [0, 0], [0, 0]], dtype=np.int32)
    first, group = row_groups(rows)
    assert first.tolist() == [0, 1, 3]
    assert group.tolist() == [0, 1, 0, 2, 1, 1]
    rng = np.random.default_rng(5)
    worlds = rng.random((50, 12)) < 0.2
    first, group = row_groups(worlds)
    assert np.array_equal(worlds[first][group], worlds)
    assert np.all(np.diff(first) > 0)
    assert group[first].tolist() == list(range(first.size))
