"""One BLAS thread while a plan runs; every library's former limit back after the last plan ends."""

from __future__ import annotations

import threading
from collections.abc import Iterator

import numpy as np
import pytest
from threadpoolctl import OpenBLASController, ThreadpoolController

from drd_planner import Planner, TableOracle, prior_from_problem
from drd_planner.data.planar_problem import make_planar_problem
from drd_planner.planner.blas_threads import blas_threads, one_blas_thread


@pytest.fixture
def two_threads() -> Iterator[None]:
    """Every loaded BLAS library at two threads for the test (so that 'one' is a change that could fail).

    The limit is set and then given up (threadpoolctl lets one Python thread at a time hold it), so that the
    test's own threads can take it as a plan would.
    """
    np.ones((4, 4)) @ np.ones((4, 4))  # numpy's BLAS is loaded
    before = blas_threads()
    assert before, "no BLAS library found in this process"
    limiter = ThreadpoolController().limit(limits=2, user_api="blas")
    OpenBLASController.clear_controlling_thread(force=True)
    assert set(blas_threads().values()) == {2}
    yield
    limiter.restore_original_limits()
    OpenBLASController.clear_controlling_thread(force=True)
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
def test_a_call_in_another_thread_limits_and_restores() -> None:
    seen: list[set[int]] = []

    @one_blas_thread
    def work() -> None:
        seen.append(set(blas_threads().values()))

    thread = threading.Thread(target=work)
    thread.start()
    thread.join(5)
    assert seen == [{1}]
    assert set(blas_threads().values()) == {2}


@pytest.mark.parametrize("last", ["owner", "other"])
@pytest.mark.usefixtures("two_threads")
def test_overlapping_calls_in_two_threads_never_leave_one_thread_behind(last: str) -> None:
    owner_in, other_in, owner_go, other_go = (threading.Event() for _ in range(4))
    seen: dict[str, set[int]] = {}

    @one_blas_thread
    def owner() -> None:
        seen["owner"] = set(blas_threads().values())
        owner_in.set()
        assert owner_go.wait(5)

    @one_blas_thread
    def other() -> None:  # starts while the owner runs: it runs under the owner's limit and changes nothing
        seen["other"] = set(blas_threads().values())
        other_in.set()
        assert other_go.wait(5)

    a, b = threading.Thread(target=owner), threading.Thread(target=other)
    a.start()
    assert owner_in.wait(5)
    b.start()
    assert other_in.wait(5)
    first, second = (owner_go, other_go) if last == "other" else (other_go, owner_go)
    first.set()
    (a if last == "other" else b).join(5)
    second.set()
    a.join(5)
    b.join(5)
    assert seen == {"owner": {1}, "other": {1}}
    assert set(blas_threads().values()) == {2}, "the process was left at one BLAS thread"


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
