"""The episode runner: stopping rules, the safety invariant and the policy contract."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.core.episode import (
    CheckRecord,
    EpisodeResult,
    GraphPathPolicy,
    TableOracle,
    append_episode,
    run_episode,
    verify_path,
)
from drd_planner.core.library import PathLibrary
from drd_planner.core.status import PlanCause, PlanStatus
from drd_planner.exceptions import PolicyError, UnverifiedPathError


class ScriptedPolicy:
    """Checks a fixed list of edges in order."""

    def __init__(self, edges: list[int]) -> None:
        self._edges = list(edges)
        self.observed: list[tuple[int, bool]] = []

    @property
    def name(self) -> str:
        return "scripted"

    @property
    def stage(self) -> str:
        return "script"

    def select(self) -> int | None:
        return self._edges.pop(0) if self._edges else None

    def observe(self, edge: int, free: bool) -> None:
        self.observed.append((edge, free))


LIB = PathLibrary.from_sequences([[0, 1], [2, 3], [1, 4]], 5)
COSTS = np.ones(5)


def test_stops_as_soon_as_a_path_is_verified() -> None:
    world = np.array([True, True, False, True, True])
    policy = ScriptedPolicy([0, 1, 2, 3, 4])
    result = run_episode(LIB, COSTS, policy, TableOracle(world))
    assert result.status is PlanStatus.FOUND
    assert result.path_index == 0
    assert [c.edge for c in result.checks] == [0, 1]
    assert policy.observed == [(0, True), (1, True)]
    np.testing.assert_array_equal(result.path_edges, [0, 1])


def test_cheapest_of_simultaneously_verified_paths_wins() -> None:
    lib = PathLibrary.from_sequences([[0, 1, 2], [1, 2]], 3)
    result = run_episode(lib, np.ones(3), ScriptedPolicy([0, 1, 2]), TableOracle([True, True, True]))
    assert result.path_index == 1  # both complete on edge 2; path 1 is cheaper


def test_no_free_path_reports_evidence_per_path() -> None:
    world = np.array([False, True, False, True, False])
    result = run_episode(LIB, COSTS, ScriptedPolicy([0, 2, 4]), TableOracle(world))
    assert result.status is PlanStatus.NO_PATH
    assert result.path_edges is None
    np.testing.assert_array_equal(result.blocked_evidence, [0, 2, 4])
    assert not result.success


def test_policy_giving_up_and_max_checks() -> None:
    world = np.ones(5, dtype=bool)
    gave_up = run_episode(LIB, COSTS, ScriptedPolicy([0]), TableOracle(world))
    assert (gave_up.status, gave_up.cause) == (PlanStatus.BUDGET_EXHAUSTED, PlanCause.POLICY_GAVE_UP)
    capped = run_episode(LIB, COSTS, ScriptedPolicy([0, 2, 1]), TableOracle(world), max_checks=2)
    assert (capped.status, capped.cause) == (PlanStatus.BUDGET_EXHAUSTED, PlanCause.CHECK_BUDGET)
    assert capped.num_checks == 2
    assert capped.ran_out is PlanCause.CHECK_BUDGET
    assert gave_up.ran_out is None  # a policy giving up is no budget running out


def test_policy_contract_violations_raise() -> None:
    world = np.ones(5, dtype=bool)
    with pytest.raises(PolicyError, match="second time"):
        run_episode(LIB, COSTS, ScriptedPolicy([0, 0]), TableOracle(world))
    with pytest.raises(PolicyError, match="outside"):
        run_episode(LIB, COSTS, ScriptedPolicy([7]), TableOracle(world))


def test_check_log_records_stage_times_and_cost() -> None:
    world = np.array([True, True, True, True, True])
    result = run_episode(LIB, np.array([1.0, 2.0, 1.0, 1.0, 1.0]), ScriptedPolicy([2, 3]), TableOracle(world))
    assert [(c.step, c.edge, c.free, c.stage) for c in result.checks] == [
        (0, 2, True, "script"),
        (1, 3, True, "script"),
    ]
    assert all(c.select_ms >= 0 and c.check_ms >= 0 for c in result.checks)
    assert result.total_cost([1.0, 2.0, 1.0, 1.0, 1.0]) == 2.0


def test_verify_path_refuses_unchecked_or_blocked_edges() -> None:
    verify_path([0, 1], {0: True, 1: True})
    with pytest.raises(UnverifiedPathError):
        verify_path([0, 1], {0: True})
    with pytest.raises(UnverifiedPathError):
        verify_path([0, 1], {0: True, 1: False})


def test_table_oracle_counts_calls() -> None:
    oracle = TableOracle([True, False])
    assert oracle.check(0) is True
    assert oracle.check(1) is False
    assert oracle.calls == 2


class ScriptedGraphPolicy(ScriptedPolicy):
    """A GraphPathPolicy that stands behind a fixed path (None: start and goal disconnected)."""

    def __init__(
        self,
        edges: list[int],
        path: list[int] | None,
        *,
        stops_on_library_path: bool = False,
        max_checks: int | None = None,
    ) -> None:
        super().__init__(edges)
        self.path = None if path is None else np.array(path, dtype=np.int64)
        self._stops = stops_on_library_path
        self._max = max_checks

    @property
    def stops_on_library_path(self) -> bool:
        return self._stops

    @property
    def max_checks(self) -> int | None:
        return self._max

    def proposed_path(self) -> np.ndarray | None:
        return self.path


def test_graph_policy_is_recognised_only_with_the_extra_members() -> None:
    assert isinstance(ScriptedGraphPolicy([], [0]), GraphPathPolicy)
    assert not isinstance(ScriptedPolicy([]), GraphPathPolicy)


def test_graph_policy_ends_on_its_own_path_not_on_a_library_path() -> None:
    world = np.ones(5, dtype=bool)
    # Library path 0 = [0, 1] is proven after two checks; the policy's own path [2, 4] after four.
    result = run_episode(LIB, COSTS, ScriptedGraphPolicy([0, 1, 2, 4, 3], [2, 4]), TableOracle(world))
    assert result.status is PlanStatus.FOUND
    assert [c.edge for c in result.checks] == [0, 1, 2, 4]
    assert result.path_index is None
    np.testing.assert_array_equal(result.path_edges, [2, 4])
    # With the flag set, the library path ends it as for any policy.
    flagged = ScriptedGraphPolicy([0, 1, 2, 4], [2, 4], stops_on_library_path=True)
    result = run_episode(LIB, COSTS, flagged, TableOracle(world))
    assert (result.num_checks, result.path_index) == (2, 0)


def test_graph_policy_blocked_library_does_not_end_it() -> None:
    # Edges 0, 2 and 1 block all three library paths; the policy's path [3] is still checked.
    world = np.array([False, False, False, True, True])
    result = run_episode(LIB, COSTS, ScriptedGraphPolicy([0, 2, 1, 3], [3]), TableOracle(world))
    assert result.status is PlanStatus.FOUND
    assert result.num_checks == 4
    np.testing.assert_array_equal(result.path_edges, [3])


def test_graph_policy_disconnected_and_budgets() -> None:
    world = np.ones(5, dtype=bool)
    gone = run_episode(LIB, COSTS, ScriptedGraphPolicy([0], None), TableOracle(world))
    assert gone.status is PlanStatus.NO_PATH
    assert gone.num_checks == 0
    assert gone.blocked_evidence is None
    assert gone.path_edges is None
    capped = run_episode(LIB, COSTS, ScriptedGraphPolicy([0, 1, 2, 3], [3], max_checks=2), TableOracle(world))
    assert (capped.status, capped.cause, capped.num_checks) == (PlanStatus.BUDGET_EXHAUSTED, PlanCause.CHECK_BUDGET, 2)
    tighter = run_episode(
        LIB, COSTS, ScriptedGraphPolicy([0, 1, 2, 3], [3], max_checks=2), TableOracle(world), max_checks=1
    )
    assert (tighter.status, tighter.cause, tighter.num_checks) == (
        PlanStatus.BUDGET_EXHAUSTED,
        PlanCause.CHECK_BUDGET,
        1,
    )
    # The path verified by the last allowed check counts as found.
    last = run_episode(LIB, COSTS, ScriptedGraphPolicy([2, 3], [2, 3], max_checks=2), TableOracle(world))
    assert last.status is PlanStatus.FOUND
    # A policy that stops asking before its path is checked gives up; nothing unverified is returned.
    quits = run_episode(LIB, COSTS, ScriptedGraphPolicy([2], [2, 3]), TableOracle(world))
    assert (quits.status, quits.cause) == (PlanStatus.BUDGET_EXHAUSTED, PlanCause.POLICY_GAVE_UP)
    assert quits.path_edges is None


def test_a_passed_deadline_ends_with_the_time_budget() -> None:
    import time

    world = np.ones(5, dtype=bool)
    late = run_episode(LIB, COSTS, ScriptedPolicy([0, 1]), TableOracle(world), deadline=time.perf_counter() - 1.0)
    assert (late.status, late.cause, late.num_checks) == (PlanStatus.BUDGET_EXHAUSTED, PlanCause.TIME_BUDGET, 0)
    assert late.ran_out is PlanCause.TIME_BUDGET
    assert late.path_edges is None


def test_a_plans_log_numbers_each_episodes_checks_on_and_keeps_their_outcomes() -> None:
    def episode(*checks: tuple[int, bool, str]) -> EpisodeResult:
        records = tuple(CheckRecord(i, e, f, stage, 0.1, 0.2) for i, (e, f, stage) in enumerate(checks))
        return EpisodeResult(records, PlanStatus.NO_PATH, None, None)

    log: list[CheckRecord] = []
    known: dict[int, bool] = {}
    append_episode(log, known, episode((4, True, "probe"), (7, False, "probe")))
    append_episode(log, known, episode((2, True, "bisect")))
    assert [(c.step, c.edge, c.free, c.stage) for c in log] == [
        (0, 4, True, "probe"),
        (1, 7, False, "probe"),
        (2, 2, True, "bisect"),
    ]
    assert known == {4: True, 7: False, 2: True}
