"""Tests of the one seeding scheme of worlds, libraries and splits."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.data.seeding import derived_seed, library_seed, split_seed, world_seeds
from drd_planner.exceptions import DatasetError


def test_world_seeds_are_deterministic_prefix_stable_and_distinct() -> None:
    a, b = world_seeds(7, 10), world_seeds(7, 25)
    assert a.dtype == np.int64
    assert np.array_equal(a, b[:10])
    assert np.unique(b).size == b.size
    assert np.all(b >= 0)
    assert not np.array_equal(world_seeds(8, 10), a)
    assert derived_seed(7, 1) != derived_seed(7, 2)
    assert int(a[3]) == int(np.random.SeedSequence(7, spawn_key=(0, 3)).generate_state(1, np.uint64)[0]) >> 1


def test_library_and_split_streams() -> None:
    assert library_seed(7) == derived_seed(7, 1)
    assert split_seed(7) == derived_seed(7, 2)
    assert 0 <= library_seed(0) < 2**63
    assert library_seed(0) != split_seed(0)


def test_negative_seed_is_refused() -> None:
    with pytest.raises(DatasetError, match="seed must be non-negative"):
        world_seeds(-1, 3)
