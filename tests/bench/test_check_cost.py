"""The stated check cost: parsing ``--check-cost-ms``, the busy-wait, the oracle wrappers and the summaries."""

from __future__ import annotations

import time

import numpy as np
import pytest

from drd_planner.bench.check_cost import (
    CostlyMotionOracle,
    CostlyOracle,
    Timed,
    burn_cpu_ms,
    cost_key,
    parse_check_costs,
    time_summary,
    timed,
    with_check_cost,
)
from drd_planner.core.episode import TableOracle
from drd_planner.exceptions import DrdError


class _Motions:
    def check(self, edge: int) -> bool:
        return edge % 2 == 0

    def check_motion(self, states: np.ndarray) -> bool:
        return bool(states.shape[0] < 3)


def test_costs_parse_in_order_without_repeats() -> None:
    assert parse_check_costs("0,0.2, 1,5,1") == (0.0, 0.2, 1.0, 5.0)
    assert [cost_key(c) for c in (0.0, 0.2, 1.0, 5.0)] == ["0", "0.2", "1", "5"]


@pytest.mark.parametrize("text", ["", "1,,2", "a", "-1", "nan", "inf", "0;1"])
def test_a_malformed_cost_names_the_valid_form(text: str) -> None:
    with pytest.raises(DrdError, match=r"--check-cost-ms: .* expected comma-separated non-negative numbers"):
        parse_check_costs(text)


def test_the_busy_wait_spends_cpu() -> None:
    c0 = time.thread_time()
    burn_cpu_ms(5.0)
    assert time.thread_time() - c0 >= 5e-3
    c0 = time.thread_time()
    burn_cpu_ms(0.0)
    assert time.thread_time() - c0 < 5e-3


def test_every_check_pays_the_cost_and_keeps_the_answer() -> None:
    row = np.array([True, False, True])
    oracle = with_check_cost(TableOracle(row), 2.0)
    assert type(oracle) is CostlyOracle
    _, spent = timed(lambda: [oracle.check(e) for e in range(3)])
    assert oracle.checks == 3
    assert oracle.log == {0: True, 1: False, 2: True}
    assert spent.cpu_ms >= 3 * 2.0


def test_motions_pay_the_cost_too() -> None:
    oracle = with_check_cost(_Motions(), 1.0)
    assert isinstance(oracle, CostlyMotionOracle)
    _, spent = timed(lambda: (oracle.check_motion(np.zeros((2, 4))), oracle.check_motion(np.zeros((5, 4)))))
    assert oracle.checks == 2
    assert spent.cpu_ms >= 2.0


def test_summaries_are_cpu_first_and_empty_is_none() -> None:
    s = time_summary([Timed(1.0, 2.0), Timed(3.0, 10.0), Timed(8.0, 3.0)])
    assert s == {"n": 3, "median": 3.0, "mean": 4.0, "wall_median": 3.0, "wall_mean": 5.0}
    assert time_summary([])["median"] is None
    assert Timed(1.0, 2.0) + Timed(3.0, 4.0) == Timed(4.0, 6.0)
