"""What one request served at once came to (planning/plan_outcome.py)."""

from __future__ import annotations

from drd_planner.core.status import PlanStatus
from drd_planner.planning.plan_outcome import PlanOutcome
from drd_planner.planning.session_plan import SessionPlan


def test_ok_only_with_a_verified_path() -> None:
    assert not PlanOutcome(refusal="no maps", refused="maps").ok
    failed = SessionPlan(status=PlanStatus.NO_PATH, message="", map_version=1, prior="t")
    assert not PlanOutcome(result=failed).ok
    found = SessionPlan(status=PlanStatus.FOUND, message="", map_version=1, prior="t")
    assert PlanOutcome(sent="path", result=found).ok
