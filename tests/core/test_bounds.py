"""The verification lower bound (drd_planner.core.bounds) on hand-worked instances."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.core.bounds import bool_matrix, oracle_lower_bound
from drd_planner.exceptions import ProblemError

# --------------------------------------------------------------------------------------------------
# oracle lower bound
# --------------------------------------------------------------------------------------------------


def test_oracle_lower_bound_small_example() -> None:
    R = np.array([[1, 0, 1], [0, 0, 0], [0, 1, 1], [1, 1, 1]], dtype=bool)
    bound = oracle_lower_bound(R, [3.0, 1.0, 2.0])
    assert bound.shape == (4,)
    assert bound[0] == 2.0
    assert bound[2] == 1.0
    assert bound[3] == 1.0
    assert np.isnan(bound[1])


def test_oracle_lower_bound_rejects_bad_shapes() -> None:
    with pytest.raises(ProblemError):
        oracle_lower_bound(np.ones((2, 3), dtype=bool), [1.0, 2.0])
    with pytest.raises(ProblemError):
        oracle_lower_bound(np.ones(3, dtype=bool), [1.0, 2.0, 3.0])


def test_bool_matrix_accepts_01_and_names_bad_input() -> None:
    assert bool_matrix("X", [[0, 1], [1, 0]]).dtype == np.bool_
    with pytest.raises(ProblemError, match="X must be a 2-D"):
        bool_matrix("X", [0, 1])
    with pytest.raises(ProblemError, match="R must hold only 0/1"):
        bool_matrix("R", [[0, 2]])
