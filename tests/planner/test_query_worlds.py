"""A query's training outcomes: the prior's columns and the new edges' beside them, never a copy of the prior's."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.core.world_columns import WorldColumns
from drd_planner.exceptions import ProblemError
from drd_planner.planner.query_worlds import QueryWorlds


def test_columns_counts_and_fractions_are_those_of_the_whole_matrix() -> None:
    rng = np.random.default_rng(1)
    base = rng.random((90, 20)) < 0.6
    extra = rng.random((90, 3)) < 0.4
    worlds = QueryWorlds(base, WorldColumns(base), extra)
    whole = np.concatenate([base, extra], axis=1)
    assert worlds.shape == (90, 23)
    assert worlds.num_base_edges == 20
    assert worlds.base is base  # the prior's matrix, not a copy
    for e in (0, 19, 20, 22):
        assert np.array_equal(worlds.column(e), whole[:, e])
    assert np.array_equal(worlds.columns([21, 3, 20]), whole[:, [21, 3, 20]])
    rows = rng.random(90) < 0.5
    assert np.array_equal(worlds.free_counts(rows), whole[rows].sum(axis=0))
    assert np.allclose(worlds.free_fraction, whole.mean(axis=0))
    assert np.array_equal(worlds.dense, whole)
    more = worlds.with_columns(rng.random((90, 2)) < 0.5)
    assert more.num_edges == 25
    assert more.base is base


def test_packed_columns_of_other_worlds_are_refused() -> None:
    base = np.ones((10, 4), dtype=bool)
    with pytest.raises(ProblemError, match="base worlds"):
        QueryWorlds(base, WorldColumns(np.ones((11, 4), dtype=bool)))
    plain = QueryWorlds(base, WorldColumns(base))
    assert plain.dense is base
    assert plain.num_edges == 4
