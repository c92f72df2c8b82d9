"""One BLAS thread while a plan runs; every library's former limit back after the last plan ends."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from drd_planner import Planner, TableOracle, prior_from_problem
from drd_planner.data.planar_problem import make_planar_problem
from drd_planner.planner.blas_threads import blas_threads, one_blas_thread


@pytest.fixture
def two_threads() -> object:
    """Every loaded BLAS library at two threads for the test (so that 'one' is a change that could fail)."""
    np.ones((4, 4)) @ np.ones((4, 4))  # numpy's BLAS is loaded
    before = blas_threads()
    assert before, "no BLAS library found in this process"
    with threadpool_limits(2, user_api="blas") as limiter:
        assert set(blas_threads().values()) == {2}
        yield limiter
    assert blas_threads() == before


@pytest.mark.usefixtures("two_threads")
def test_a_decorated_call_runs_with_one_thread_and_restores_two() -> None:
    @one_blas_thread
    def inside(x: int) -> dict[str, int]:
        """Returns what it saw."""
        return blas_threads() | {"x": x}

    seen = inside(5)
    assert seen.pop("x") == 5
    assert set(seen.values()) == {1}
    assert set(blas_threads().values()) == {2}
    assert inside.__doc__ == "Returns what it saw."


@pytest.mark.usefixtures("two_threads")
def test_an_error_inside_still_restores_the_limits() -> None:
    @one_blas_thread
    def fails() -> None:
        raise ValueError("boom")

    with pytest.raises(ValueError, match="boom"):
        fails()
    assert set(blas_threads().values()) == {2}


@pytest.mark.usefixtures("two_threads")
def test_overlapping_calls_from_two_threads_keep_one_until_the_last_ends() -> None:
    first_in, second_in, first_out = threading.Event(), threading.Event(), threading.Event()
    seen: dict[str, set[int]] = {}

    @one_blas_thread
    def first() -> None:
        first_in.set()
        assert second_in.wait(5)

    @one_blas_thread
    def second() -> None:
        second_in.set()
        assert first_out.wait(5)  # the first call has ended: this one still runs with one thread
        seen["second, after the first ended"] = set(blas_threads().values())

    a = threading.Thread(target=first)
    b = threading.Thread(target=second)
    a.start()
    assert first_in.wait(5)
    b.start()
    a.join(5)
    first_out.set()
    b.join(5)
    assert seen["second, after the first ended"] == {1}
    assert set(blas_threads().values()) == {2}


@pytest.mark.usefixtures("two_threads")
def test_a_plan_checks_with_one_blas_thread_and_leaves_the_callers_limits() -> None:
    problem = make_planar_problem(model="forest", num_worlds=60, seed=3)
    prior = prior_from_problem(problem, domain="planar", trees=(), eta=1.0)
    world = problem.require_worlds().X[int(problem.require_worlds().test_ids[0])]
    during: list[set[int]] = []

    class Watching(TableOracle):
        def check(self, edge: int) -> bool:
            during.append(set(blas_threads().values()))
            return super().check(edge)

    planner = Planner(prior)
    assert problem.start is not None
    assert problem.goal is not None
    result = planner.plan(problem.start, problem.goal, Watching(world))
    assert result.num_checks > 0
    assert during
    assert all(s == {1} for s in during)
    assert set(blas_threads().values()) == {2}
    graph = planner.query_graph(problem.start, problem.goal)
    assert graph.graph.num_edges == prior.graph.num_edges
    assert set(blas_threads().values()) == {2}
