"""Bisection order of trajectory samples."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.exceptions import GeometryError
from drd_planner.geometry.ordering import bisection_order, bisection_rank


def test_known_orders() -> None:
    assert bisection_order(7).tolist() == [3, 1, 5, 0, 2, 4, 6]
    assert bisection_order(1).tolist() == [0]
    assert bisection_order(0).tolist() == []
    assert bisection_order(4).tolist() == [1, 0, 2, 3]


@pytest.mark.parametrize("n", [2, 5, 30, 31, 100])
def test_order_is_a_permutation_and_rank_its_inverse(n: int) -> None:
    order = bisection_order(n)
    assert sorted(order.tolist()) == list(range(n))
    np.testing.assert_array_equal(bisection_rank(n)[order], np.arange(n))
    # the first samples are spread out: the first three split the range roughly in quarters
    if n >= 7:
        assert abs(order[0] - (n - 1) / 2) <= 1


def test_results_are_read_only_and_input_checked() -> None:
    with pytest.raises(ValueError, match="read-only"):
        bisection_order(5)[0] = 1
    with pytest.raises(GeometryError, match="count"):
        bisection_order(-1)
