"""A session's result: counts read from its check log, and the deprecated name of its prior."""

from __future__ import annotations

from drd_planner.core.status import PlanStatus
from drd_planner.planning.session_plan import SessionCheck, SessionPlan


def _check(step: int, free: bool) -> SessionCheck:
    return SessionCheck(step, 10 + step, (step, step + 1), free, "bisect", 0.5, 0.1, False)


def test_blocked_checks_are_counted_from_the_log() -> None:
    checks = tuple(_check(k + 1, free) for k, free in enumerate([True, False, True, False, False]))
    plan = SessionPlan(status=PlanStatus.NO_PATH, message="", map_version=3, prior="heli", checks=checks)
    assert plan.num_blocked == 3
    assert SessionPlan(status=PlanStatus.REFUSED, message="", map_version=3, prior="heli").num_blocked == 0


def test_the_prior_keeps_its_old_name_tree_for_one_release() -> None:
    plan = SessionPlan(status=PlanStatus.FOUND, message="", map_version=1, prior="heli_lines")
    assert plan.tree == plan.prior == "heli_lines"
    assert plan.states.shape == (0, 3)
    assert (plan.query, plan.stage, plan.cost, plan.improvements) == ("", "", 0.0, 0)
