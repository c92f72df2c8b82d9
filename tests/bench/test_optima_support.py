"""Validation and bitmask helpers of the exact optima (drd_planner.bench.optima_support)."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.bench.optima_support import (
    MAX_LIBRARY_EDGES,
    WorldMass,
    bits,
    check_costs,
    check_library,
    check_prior,
    check_theta,
    column_masks,
    local_path_masks,
    path_library,
)
from drd_planner.exceptions import ProblemError


def test_bitmask_helpers() -> None:
    assert bits(0) == []
    assert bits(0b101001) == [0, 3, 5]
    x = np.array([[1, 0], [1, 1], [0, 1]], dtype=bool)
    assert column_masks(x) == [0b011, 0b110]
    library = path_library([[4, 2], [7]], 8)
    edges, masks = local_path_masks(library)
    assert edges == [2, 4, 7]
    assert masks == [0b011, 0b100]


def test_world_mass_sums_the_masked_weights() -> None:
    weights = np.arange(1.0, 20.0)  # spans three byte tables
    mass = WorldMass(weights)
    rng = np.random.default_rng(0)
    for mask in rng.integers(0, 1 << weights.size, 50).tolist():
        assert mass(mask) == pytest.approx(sum(weights[j] for j in bits(mask)))
    assert mass(0) == 0.0


def test_validation_names_the_bad_input() -> None:
    assert check_costs([1.0, 2.0], 2).dtype == np.float64
    with pytest.raises(ProblemError, match="shape"):
        check_costs([1.0], 2)
    with pytest.raises(ProblemError, match="positive"):
        check_costs([1.0, 0.0], 2)
    assert check_prior(None, 3).tolist() == [1.0, 1.0, 1.0]
    with pytest.raises(ProblemError, match="positive sum"):
        check_prior([0.0, 0.0], 2)
    with pytest.raises(ProblemError, match="1-D"):
        check_theta([[0.5]])
    with pytest.raises(ProblemError, match="probabilities"):
        check_theta([1.5])
    with pytest.raises(ProblemError, match="integer edge ids"):
        path_library([[0.5, 1.0]], 3)  # type: ignore[list-item]
    big = MAX_LIBRARY_EDGES + 1
    with pytest.raises(ProblemError, match="distinct edges"):
        check_library([[e] for e in range(big)], big)
