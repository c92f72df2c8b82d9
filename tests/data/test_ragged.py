"""Tests of the one ragged-array packer."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.data.ragged import pack_ragged, unpack_ragged
from drd_planner.exceptions import DatasetError


def test_pack_and_unpack_round_trip() -> None:
    parts = [np.array([1, 2, 3]), np.array([], dtype=np.int64), np.array([7])]
    flat, offsets = pack_ragged(parts, np.int64)
    assert flat.dtype == np.int64
    assert flat.tolist() == [1, 2, 3, 7]
    assert offsets.tolist() == [0, 3, 3, 4]
    back = unpack_ragged(flat, offsets, 3, "path", DatasetError)
    assert [b.tolist() for b in back] == [[1, 2, 3], [], [7]]
    assert [b.tolist() for b in unpack_ragged(flat, offsets, None, "path", DatasetError)] == [
        [1, 2, 3],
        [],
        [7],
    ]


def test_tuples_rows_and_no_parts() -> None:
    flat, offsets = pack_ragged([(4, 5), (6,)], np.int64)
    assert flat.tolist() == [4, 5, 6]
    assert offsets.tolist() == [0, 2, 3]
    rows, row_offsets = pack_ragged([np.zeros((2, 3)), np.ones((1, 3))], np.float64)
    assert rows.shape == (3, 3)
    assert row_offsets.tolist() == [0, 2, 3]
    empty, empty_offsets = pack_ragged([], np.int64)
    assert empty.shape == (0,)
    assert empty.dtype == np.int64
    assert empty_offsets.tolist() == [0]


@pytest.mark.parametrize(
    ("offsets", "count"),
    [([0, 2], 2), ([1, 4], 1), ([0, 5], 1), ([0, 3, 2, 4], 3), ([0], None), ([[0, 4]], None)],
)
def test_bad_offsets_are_refused(offsets: list[int], count: int | None) -> None:
    with pytest.raises(DatasetError, match="library path offsets do not partition"):
        unpack_ragged(np.arange(4), np.array(offsets, dtype=np.int64), count, "library path", DatasetError)
