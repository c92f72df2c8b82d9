"""The one status vocabulary: the planner's names still reach it, and the budget causes are told apart."""

from __future__ import annotations

import drd_planner
import drd_planner.planner
from drd_planner.core.status import PlanCause, PlanStatus
from drd_planner.planner import cause, result


def test_the_planner_and_the_package_re_export_the_core_enums() -> None:
    assert drd_planner.PlanStatus is PlanStatus
    assert drd_planner.planner.PlanStatus is PlanStatus
    assert result.PlanStatus is PlanStatus
    assert cause.PlanCause is PlanCause


def test_values_are_the_wire_text() -> None:
    assert [s.value for s in PlanStatus] == ["found", "no_path", "budget_exhausted", "refused"]
    assert PlanStatus("no_path") is PlanStatus.NO_PATH
    assert PlanCause("check_budget") is PlanCause.CHECK_BUDGET


def test_only_the_check_and_time_budgets_are_budgets() -> None:
    budgets = {c for c in PlanCause if c.is_budget}
    assert budgets == {PlanCause.CHECK_BUDGET, PlanCause.TIME_BUDGET}
    assert not PlanCause.POLICY_GAVE_UP.is_budget  # the policy stopped; no budget ran out


def test_causes_by_end() -> None:
    assert PlanCause.outside("start") is PlanCause.START_OUTSIDE
    assert PlanCause.outside("goal") is PlanCause.GOAL_OUTSIDE
    assert PlanCause.blocked("start") is PlanCause.START_BLOCKED
    assert PlanCause.blocked("goal") is PlanCause.GOAL_BLOCKED
