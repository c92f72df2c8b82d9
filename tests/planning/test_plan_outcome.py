"""What one request served at once came to (planning/plan_outcome.py)."""

from __future__ import annotations

from drd_planner.planning.plan_outcome import PlanOutcome
from drd_planner.planning.query_session import QueryPlanResult


def test_ok_only_with_a_verified_path() -> None:
    assert not PlanOutcome(refusal="no maps", refused="maps").ok
    failed = QueryPlanResult(ok=False, status="no_free_path", message="", map_version=1, prior="t")
    assert not PlanOutcome(result=failed).ok
    found = QueryPlanResult(ok=True, status="path_found", message="", map_version=1, prior="t")
    assert PlanOutcome(sent="path", result=found).ok
