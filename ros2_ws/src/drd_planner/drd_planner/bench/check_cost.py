"""A stated CPU cost per collision check: ``drd bench --check-cost-ms C[,C...]`` and its timing helpers.

A real checker costs far more than a row of X; to compare time to a verified plan at a known check cost,
every check is made to spend ``C`` ms of CPU on top of the oracle's own answer (a busy-wait on this thread's
CPU clock, so the cost holds on a loaded machine too). The wait runs inside the oracle wrapper
(:func:`with_check_cost`), so every policy pays it once per check it makes, and the OMPL worker's motion
validator pays it once per distinct edge it asks about (:mod:`drd_planner.bench.ompl_worker`).

Times are CPU time of this process (``time.process_time``, the main number on a shared machine) with the
wall time beside it, both in ms.
"""

from __future__ import annotations

import gc
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.core.episode import EdgeOracle
from drd_planner.exceptions import DrdError
from drd_planner.planner.connect import MotionOracle

__all__ = [
    "CHECK_COST_FORM",
    "CostlyMotionOracle",
    "CostlyOracle",
    "Timed",
    "burn_cpu_ms",
    "cost_key",
    "parse_check_costs",
    "time_summary",
    "timed",
    "with_check_cost",
]

#: The valid form of ``--check-cost-ms``, quoted in its error.
CHECK_COST_FORM = "comma-separated non-negative numbers of milliseconds, e.g. 0,0.2,1,5"

T = TypeVar("T")


def parse_check_costs(text: str) -> tuple[float, ...]:
    """The costs (ms per check) of ``--check-cost-ms``: distinct, in the order given.

    Raises:
        DrdError: an empty list, a value that is not a number, negative or not finite.
    """
    values: list[float] = []
    for part in text.split(","):
        word = part.strip()
        try:
            value = float(word)
        except ValueError:
            raise DrdError(f"--check-cost-ms: {word!r} is not a number; expected {CHECK_COST_FORM}") from None
        if not (math.isfinite(value) and value >= 0.0):
            raise DrdError(f"--check-cost-ms: {word!r} is not a non-negative number; expected {CHECK_COST_FORM}")
        if value not in values:
            values.append(value)
    return tuple(values)


def cost_key(cost_ms: float) -> str:
    """The JSON key of a check cost: ``0``, ``0.2``, ``1``, ``5`` (shortest form)."""
    return f"{cost_ms:g}"


def burn_cpu_ms(cost_ms: float) -> None:
    """Spend ``cost_ms`` ms of this thread's CPU time (a busy-wait; returns at once for 0)."""
    if cost_ms <= 0.0:
        return
    end = time.thread_time() + cost_ms * 1e-3
    while time.thread_time() < end:
        pass


class CostlyOracle:
    """An edge oracle that spends ``cost_ms`` ms of CPU before each answer of ``oracle``.

    Args:
        oracle: the oracle answering (a row of X, a live checker).
        cost_ms: the added CPU per check (ms).

    Attributes:
        checks: the checks answered so far (edges and motions).
        log: graph edge id -> the answer, for every edge checked by id.
    """

    def __init__(self, oracle: EdgeOracle, cost_ms: float) -> None:
        self.oracle = oracle
        self.cost_ms = float(cost_ms)
        self.checks = 0
        self.log: dict[int, bool] = {}

    def check(self, edge: int) -> bool:
        """The wrapped oracle's answer for ``edge``, after ``cost_ms`` ms of CPU."""
        burn_cpu_ms(self.cost_ms)
        self.checks += 1
        free = bool(self.oracle.check(edge))
        self.log[int(edge)] = free
        return free


class CostlyMotionOracle(CostlyOracle):
    """A :class:`CostlyOracle` over an oracle that checks motions too (off-graph queries): they cost the same."""

    def check_motion(self, states: FloatArray) -> bool:
        """The wrapped oracle's answer for the (K, D) motion ``states``, after ``cost_ms`` ms of CPU."""
        burn_cpu_ms(self.cost_ms)
        self.checks += 1
        oracle = self.oracle
        assert isinstance(oracle, MotionOracle)
        return bool(oracle.check_motion(states))


def with_check_cost(oracle: EdgeOracle, cost_ms: float) -> CostlyOracle:
    """``oracle`` with ``cost_ms`` ms of CPU per check (a :class:`CostlyMotionOracle` when it checks motions)."""
    if isinstance(oracle, MotionOracle):
        return CostlyMotionOracle(oracle, cost_ms)
    return CostlyOracle(oracle, cost_ms)


@dataclass(frozen=True)
class Timed:
    """CPU and wall time of one call, in ms."""

    cpu_ms: float
    wall_ms: float

    def __add__(self, other: Timed) -> Timed:
        return Timed(self.cpu_ms + other.cpu_ms, self.wall_ms + other.wall_ms)


def timed(fn: Callable[[], T]) -> tuple[T, Timed]:
    """``fn()`` and the CPU (``time.process_time``) and wall time it took.

    Python's garbage is collected first (not timed), so that a collection during ``fn`` is of ``fn``'s own
    garbage, not of what the episodes before it left behind.
    """
    gc.collect()
    c0, w0 = time.process_time(), time.perf_counter()
    out = fn()
    return out, Timed(1e3 * (time.process_time() - c0), 1e3 * (time.perf_counter() - w0))


def time_summary(times: Sequence[Timed]) -> dict[str, Any]:
    """``{"n", "median", "mean", "wall_median", "wall_mean"}`` in ms (CPU first; None when empty)."""
    cpu = np.array([t.cpu_ms for t in times], dtype=np.float64)
    wall = np.array([t.wall_ms for t in times], dtype=np.float64)

    def stat(values: FloatArray, fn: Callable[[FloatArray], Any]) -> float | None:
        return float(fn(values)) if values.size else None

    return {
        "n": int(cpu.size),
        "median": stat(cpu, np.median),
        "mean": stat(cpu, np.mean),
        "wall_median": stat(wall, np.median),
        "wall_mean": stat(wall, np.mean),
    }
