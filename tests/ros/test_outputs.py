"""The node's outputs: the plan summary's values (what monitors and the tests read)."""

from __future__ import annotations

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")

from drd_planner.planning.query_session import QueryPlanResult
from drd_planner.planning.session import SessionCheck
from drd_planner.ros.outputs import plan_summary_values


def _check(step: int, free: bool, stage: str) -> SessionCheck:
    return SessionCheck(step, step, (0, 1), free, stage, 0.5, 0.1, False)


def test_summary_counts_checks_by_outcome_and_stage_and_gives_planning_time() -> None:
    checks = (_check(1, True, "tree"), _check(2, False, "tree"), _check(3, True, "bisect"))
    result = QueryPlanResult(
        ok=True,
        status="path_found",
        message="found",
        map_version=3,
        tree="heli",
        path_edges=(1, 3),
        checks=checks,
        seconds={"total": 0.25, "checks": 0.0015, "library": 0.125},
        stage="bisect",
        query="online",
    )
    values = plan_summary_values(
        result, {"request": "goal_pose"}, wait_s=0.01, plan_messaging_s=0.002, messaging_s=0.003
    )
    assert (values["checks"], values["free"], values["blocked"]) == (3, 2, 1)
    assert (values["tree_checks"], values["bisect_checks"]) == (2, 1)
    assert values["planning_time"] == values["total_s"] == "0.250000"
    assert (values["query"], values["stage"], values["library_s"]) == ("online", "bisect", "0.125000")
    assert (
        values["result"] == "path_found" and values["request"] == "goal_pose" and values["map_version"] == 3
    )


def test_summary_reports_the_anytime_improvement_only_when_it_ran() -> None:
    checks = (_check(1, True, "tree"), _check(2, True, "improve"), _check(3, False, "improve"))
    common = {"ok": True, "status": "path_found", "message": "found", "map_version": 1, "tree": "heli"}
    plain = plan_summary_values(
        QueryPlanResult(**common, checks=checks[:1], cost=751.1),  # type: ignore[arg-type]
        {"request": "goal_pose"},
        wait_s=0.0,
        plan_messaging_s=0.0,
        messaging_s=0.0,
    )
    assert not {"improvements", "improve_stop", "improve_checks", "first_cost", "cost"} & set(plain)
    improved = QueryPlanResult(
        **common,  # type: ignore[arg-type]
        checks=checks,
        stage="improve",
        cost=700.0,
        first_cost=751.1,
        improvements=2,
        improve_stop="optimal",
    )
    values = plan_summary_values(
        improved, {"request": "goal_pose"}, wait_s=0.0, plan_messaging_s=0.0, messaging_s=0.0
    )
    assert (values["improvements"], values["improve_stop"], values["improve_checks"]) == (2, "optimal", 2)
    assert (values["first_cost"], values["cost"]) == ("751.100000", "700.000000")
    assert list(values)[-1] == "request"  # the request's own values stay last
