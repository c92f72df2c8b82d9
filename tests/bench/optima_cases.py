"""Shared instances and reference helpers of the exact-optima tests (tests/bench/test_optima*.py)."""

from __future__ import annotations

import itertools
from collections.abc import Callable

import numpy as np
import numpy.typing as npt

from drd_planner.core.bisect import Bisect
from drd_planner.core.library import PathLibrary

#: Absolute tolerance of the exact comparisons.
TOL = 1e-9


def random_paths(rng: np.random.Generator, num_edges: int, num_paths: int, max_len: int) -> list[list[int]]:
    """``num_paths`` random paths of 1..max_len distinct edges out of ``num_edges``."""
    return [
        sorted(rng.choice(num_edges, size=int(rng.integers(1, min(max_len, num_edges) + 1)), replace=False))
        for _ in range(num_paths)
    ]


def all_worlds(num_edges: int) -> npt.NDArray[np.bool_]:
    """(2^E, E) every outcome vector."""
    return np.array(list(itertools.product([False, True], repeat=num_edges)), dtype=bool).reshape(-1, num_edges)


def bernoulli_prior(worlds: npt.NDArray[np.bool_], theta: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """Probability of each outcome vector under independent edges."""
    return np.asarray(np.prod(np.where(worlds, theta, 1.0 - theta), axis=1), dtype=np.float64)


def bisect_factory(
    library: PathLibrary,
    theta: npt.NDArray[np.float64],
    costs: npt.NDArray[np.float64],
    max_prob_region: bool,
) -> Callable[[dict[int, bool]], Bisect]:
    """Builds a BiSECt selector that has heard the given observations."""

    def make(obs: dict[int, bool]) -> Bisect:
        return Bisect(library, theta, costs, max_prob_region=max_prob_region, observations=obs)

    return make
