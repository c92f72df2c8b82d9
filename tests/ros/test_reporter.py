"""The node's outputs of the planner service: the plan first, then the check log, markers and summary."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")

from drd_planner.core.status import PlanStatus
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.service import PlanRecord
from drd_planner.ros.reporter import NodeReporter


class _Outputs:
    """Stands in for PlannerOutputs: records what would be published, in order."""

    def __init__(self, *, active: bool) -> None:
        self.active = active
        self.sent: list[tuple[str, Any]] = []

    def stamp(self) -> tuple[int, int]:
        return (7, 9)

    def plan(self, session: Any, result: Any, snapshot: Any, stamp: tuple[int, int]) -> str:
        self.sent.append(("plan", stamp))
        return "path"

    def checks(self, result: Any, stamp: tuple[int, int]) -> None:
        self.sent.append(("checks", stamp))

    def markers(self, session: Any, result: Any, snapshot: Any, stamp: tuple[int, int]) -> None:
        self.sent.append(("markers", stamp))

    def status(self, topic: str, *, ok: bool, message: str, values: Any, stamp: Any = None) -> None:
        self.sent.append((topic, values))

    def withdraw(self, session: Any) -> None:
        self.sent.append(("withdraw", session))


class _Logger:
    def __init__(self) -> None:
        self.lines: list[str] = []

    def info(self, text: str) -> None:
        self.lines.append(f"info {text}")

    def warning(self, text: str) -> None:
        self.lines.append(f"warning {text}")


def _result(ok: bool) -> Any:
    return SimpleNamespace(
        ok=ok,
        status=PlanStatus.FOUND if ok else PlanStatus.NO_PATH,
        outcome="found" if ok else "no_path",
        cause=None,
        message="m",
        prior="t",
        query="q",
        stage="s",
        map_version=1,
        checks=(),
        num_blocked=0,
        seconds={},
        improve_stop="",
    )


def test_a_found_plan_goes_out_first_and_the_summary_last() -> None:
    outputs, logger, errors = _Outputs(active=True), _Logger(), []
    reporter = NodeReporter(logger, outputs, lambda text, topic: errors.append((text, topic)), lambda text, exc: None)  # type: ignore[arg-type]
    session = SimpleNamespace(name="t")
    record = PlanRecord(session, _result(True), MapSnapshot(1), {"request": "goal_pose"})  # type: ignore[arg-type]

    def publish(stamp: tuple[int, int]) -> Any:
        path, out_there = reporter.plan(session, record.result, MapSnapshot(1), stamp)  # type: ignore[arg-type]
        assert out_there
        return path

    assert reporter.result(record, wait_s=0.5, publish=publish) == "path"
    assert [k for k, _ in outputs.sent] == ["plan", "checks", "markers", "plan"]
    summary = outputs.sent[-1][1]
    assert summary["result"] == "found"
    assert summary["wait_s"] == "0.500000"
    assert summary["request"] == "goal_pose"
    assert summary["prior"] == "t"
    assert summary["tree"] == "t"  # the deprecated key, kept for one release
    assert reporter.last_plan is not None
    assert reporter.last_plan.request == "goal_pose"
    assert logger.lines == ["info t: m"]
    assert not errors
    reporter.error("bad", "maps")
    reporter.withdraw(session)  # type: ignore[arg-type]
    assert errors == [("bad", "maps")]
    assert outputs.sent[-1] == ("withdraw", session)


def test_no_plan_is_logged_as_a_warning() -> None:
    outputs, logger = _Outputs(active=False), _Logger()
    reporter = NodeReporter(logger, outputs, lambda text, topic: None, lambda text, exc: None)  # type: ignore[arg-type]
    record = PlanRecord(SimpleNamespace(name="t"), _result(False), MapSnapshot(1), {})  # type: ignore[arg-type]
    assert reporter.result(record, wait_s=0.0, publish=lambda stamp: None) is None
    assert logger.lines == ["warning t: m; nothing published on plan"]


def test_a_bug_goes_to_the_nodes_bug_report_with_its_exception() -> None:
    bugs: list[tuple[str, BaseException]] = []
    errors: list[tuple[str, str]] = []
    reporter = NodeReporter(
        _Logger(),
        _Outputs(active=True),  # type: ignore[arg-type]
        lambda text, topic: errors.append((text, topic)),
        lambda text, exc: bugs.append((text, exc)),
    )
    exc = RuntimeError("broken")
    reporter.bug("goal_pose: internal error", exc)
    assert bugs == [("goal_pose: internal error", exc)]
    assert not errors
