"""Reverse-tree rows kept over the vertices each search covered: read back exactly, unknown elsewhere."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.planner import tree_rows
from drd_planner.planner.tree_rows import TreeRows
from drd_planner.planner.union_paths import NO_HOP


def test_rows_read_back_what_each_search_wrote_and_unknown_elsewhere() -> None:
    rows = TreeRows(4, 6)
    assert not rows.searched.any()
    assert np.isinf(rows.dist_at(np.arange(6))).all()
    rows.add(
        np.array([2, 0]),
        np.array([1, 3, 5]),
        np.array([[1.0, 2.0, 0.0], [4.0, 5.0, 0.0]]),
        np.array([[3, 5, NO_HOP], [3, 5, NO_HOP]], dtype=np.int32),
        0.0,
    )
    rows.add(
        np.array([3]), np.arange(6), np.arange(6, dtype=float)[None, :] + 10, np.zeros((1, 6), dtype=np.int32), np.inf
    )
    assert rows.searched.tolist() == [True, False, True, True]
    table = rows.dist_at(np.array([0, 1, 3]))
    assert np.isinf(table[0, 0])
    assert table[0, 1] == 4.0
    assert table[0, 2] == 5.0
    assert np.isinf(table[1]).all()
    assert table[2, 1:].tolist() == [1.0, 2.0]
    assert table[3].tolist() == [10.0, 11.0, 13.0]
    assert rows.dist_of(np.array([2, 3, 0]), np.array([3, 4, 4])).tolist() == [2.0, 14.0, np.inf]
    assert rows.hop_of(np.array([2, 0, 3]), np.array([1, 0, 2])).tolist() == [3, NO_HOP, 0]
    assert rows.radius.tolist() == [0.0, 0.0, 0.0, np.inf]


def test_a_world_searched_again_reads_its_new_row() -> None:
    rows = TreeRows(2, 4)
    rows.add(
        np.array([0, 1]),
        np.array([0, 1]),
        np.array([[0.0, 1.0], [0.0, 2.0]]),
        np.array([[-1, 0], [-1, 0]], dtype=np.int32),
        1.5,
    )
    rows.add(
        np.array([1]), np.arange(4), np.array([[0.0, 2.0, 3.0, 4.0]]), np.array([[-1, 0, 1, 2]], dtype=np.int32), np.inf
    )
    assert rows.dist_at(np.arange(4)).tolist() == [[0.0, 1.0, np.inf, np.inf], [0.0, 2.0, 3.0, 4.0]]
    assert rows.hop_of(np.array([1, 0]), np.array([3, 3])).tolist() == [2, NO_HOP]
    assert rows.radius.tolist() == [1.5, np.inf]


def test_a_nan_distance_is_unknown_and_inf_is_known_unreachable() -> None:
    rows = TreeRows(1, 3)
    rows.add(
        np.array([0]),
        np.array([0, 1, 2]),
        np.array([[0.0, np.nan, np.inf]]),
        np.array([[NO_HOP, NO_HOP, NO_HOP]], dtype=np.int32),
        0.0,
    )
    assert rows.known_at(np.array([0, 1, 2])).tolist() == [[True, False, True]]
    assert rows.dist_at(np.array([0, 1, 2])).tolist() == [[0.0, np.inf, np.inf]]
    assert rows.dist_of(np.array([0]), np.array([1])).tolist() == [np.inf]


def test_rows_replaced_again_and_again_stay_bounded_and_read_the_same(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(tree_rows, "COMPACT_SLACK", 0)
    rows = TreeRows(3, 50)
    rng = np.random.default_rng(0)
    latest: dict[int, np.ndarray] = {}
    for _ in range(200):  # a robot replanning: a world searched again and again
        world = int(rng.integers(3))
        vertices = np.sort(rng.choice(50, size=int(rng.integers(1, 50)), replace=False))
        dist = rng.random((1, vertices.size))
        rows.add(np.array([world]), vertices, dist, np.zeros((1, vertices.size), dtype=np.int32), 0.0)
        full = np.full(50, np.inf)
        full[vertices] = dist[0]
        latest[world] = full
    assert rows.stored_entries <= 2 * 3 * 50
    for world, full in latest.items():
        assert rows.dist_at(np.arange(50))[world].tolist() == full.tolist()
