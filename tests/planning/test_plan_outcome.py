"""What one request served at once came to (planning/plan_outcome.py)."""

from __future__ import annotations

from drd_planner.planning.plan_outcome import PlanOutcome
from drd_planner.planning.session_plan import SessionPlan


def test_ok_only_with_a_verified_path() -> None:
    assert not PlanOutcome(refusal="no maps", refused="maps").ok
    failed = SessionPlan(ok=False, status="no_free_path", message="", map_version=1, prior="t")
    assert not PlanOutcome(result=failed).ok
    found = SessionPlan(ok=True, status="path_found", message="", map_version=1, prior="t")
    assert PlanOutcome(sent="path", result=found).ok
