"""The one seeding scheme of sampled worlds, path libraries and train/test splits.

Every seed comes from ``numpy.random.SeedSequence`` (``>> 1`` keeps it in [0, 2**63)):

* world i: ``SeedSequence(seed, spawn_key=(0, i)).generate_state(1, np.uint64)[0] >> 1``; it depends
  only on ``seed`` and ``i``, so the first n worlds are the same whatever the number of worlds;
* library subsample: the same with ``spawn_key=(1,)``; train/test split: ``spawn_key=(2,)``.

``drd build-dataset`` and ``drd demo`` both draw their worlds with it, so the same seed gives the same
worlds in both.
"""

from __future__ import annotations

import numpy as np

from drd_planner.arrays import IntArray
from drd_planner.exceptions import DatasetError

__all__ = [
    "LIBRARY_STREAM",
    "SPLIT_STREAM",
    "WORLD_SEED_RULE",
    "WORLD_STREAM",
    "derived_seed",
    "library_seed",
    "split_seed",
    "world_seeds",
]

#: The first spawn-key entry of each seed stream.
WORLD_STREAM, LIBRARY_STREAM, SPLIT_STREAM = 0, 1, 2

#: The world-seed rule in words, as recorded in a dataset's provenance.
WORLD_SEED_RULE = "SeedSequence(seed, spawn_key=(0, i)).generate_state(1, uint64)[0] >> 1"


def derived_seed(seed: int, *spawn_key: int) -> int:
    """A seed in [0, 2**63) derived from ``seed`` and ``spawn_key`` (see the module docstring)."""
    state = np.random.SeedSequence(seed, spawn_key=spawn_key).generate_state(1, dtype=np.uint64)
    return int(state[0]) >> 1


def world_seeds(seed: int, num_worlds: int) -> IntArray:
    """(num_worlds,) int64 seeds of the worlds 0..num_worlds-1; world i's seed depends on (seed, i) only.

    Raises:
        DatasetError: ``seed`` is negative.
    """
    if seed < 0:
        raise DatasetError(f"seed must be non-negative, got {seed}")
    return np.array([derived_seed(seed, WORLD_STREAM, i) for i in range(num_worlds)], dtype=np.int64)


def library_seed(seed: int) -> int:
    """The seed of the path library's uniform subsample."""
    return derived_seed(seed, LIBRARY_STREAM)


def split_seed(seed: int) -> int:
    """The seed of the train/test split."""
    return derived_seed(seed, SPLIT_STREAM)
