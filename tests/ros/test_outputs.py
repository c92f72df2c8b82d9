"""The node's outputs: plans sent serialized (decoded equal to the messages), the plan summary's values."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")

from diagnostic_msgs.msg import DiagnosticArray
from nav_msgs.msg import Path
from rclpy.serialization import deserialize_message
from trajectory_msgs.msg import JointTrajectory

from drd_msgs_py.factory import RclpyMessages
from drd_msgs_py.plans import (
    CheckRecord,
    diagnostics_message,
    edge_checks_message,
    joint_trajectory_message,
    summary_status,
)
from drd_planner.core.status import PlanStatus
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.session_plan import SessionCheck, SessionPlan
from drd_planner.ros.outputs import TRAJECTORY_JOINT_SPEED, PlannerOutputs, plan_summary_values


class _Publisher:
    def __init__(self, topic: str, sent: list[tuple[str, Any]]) -> None:
        self.topic, self.sent, self.is_activated = topic, sent, True

    def publish(self, msg: Any) -> None:
        self.sent.append((self.topic, msg))

    def get_subscription_count(self) -> int:
        return 0


class _Node:
    """Stands in for the lifecycle node: its publishers record what they are given."""

    def __init__(self) -> None:
        self.sent: list[tuple[str, Any]] = []

    def create_lifecycle_publisher(self, kind: Any, topic: str, qos: Any) -> _Publisher:
        return _Publisher(topic, self.sent)

    def create_publisher(self, kind: Any, topic: str, qos: Any) -> _Publisher:
        return _Publisher(topic, self.sent)

    def get_name(self) -> str:
        return "planner"

    def get_clock(self) -> Any:
        return SimpleNamespace(now=lambda: SimpleNamespace(seconds_nanoseconds=lambda: (6, 7)))


def test_a_helicopter_plan_goes_out_as_bytes_of_the_path_its_message_gives() -> None:
    node = _Node()
    outputs = PlannerOutputs(node, frame="map")
    states = np.array([[0.0, 0.0, 50.0, 0.0], [10.0, 5.0, 55.0, 0.5], [20.0, 10.0, 60.0, 1.0]])
    session = SimpleNamespace(domain=SimpleNamespace(publishes_joint_trajectory=False))
    sent = outputs.plan(session, SimpleNamespace(states=states), MapSnapshot(1), (4, 5))  # type: ignore[arg-type]
    [(topic, data)] = node.sent
    assert topic == "plan"
    assert isinstance(data, bytes)
    path = sent.path()
    assert deserialize_message(data, Path) == path
    assert len(path.poses) == 3
    assert (path.header.frame_id, path.header.stamp.sec, path.poses[2].pose.position.z) == ("map", 4, 60.0)
    outputs.withdraw(session)  # type: ignore[arg-type]
    assert node.sent[-1][0] == "plan"
    assert len(deserialize_message(node.sent[-1][1], Path).poses) == 0


def test_an_arm_plan_sends_its_trajectory_then_its_tool_path() -> None:
    node = _Node()
    outputs = PlannerOutputs(node, frame="panda_link0")
    q = np.linspace(0.0, 1.0, 14).reshape(7, 2)
    tool = np.column_stack([q, np.ones(7)])
    session = SimpleNamespace(
        joint_names=("j1", "j2"),
        domain=SimpleNamespace(resolution=0.05, publishes_joint_trajectory=True),
        positions=lambda states, snapshot: tool,
    )
    sent = outputs.plan(session, SimpleNamespace(states=q), MapSnapshot(1), (4, 5))  # type: ignore[arg-type]
    assert [topic for topic, _ in node.sent] == ["joint_trajectory", "plan"]
    trajectory = deserialize_message(node.sent[0][1], JointTrajectory)
    expected = joint_trajectory_message(
        ["j1", "j2"],
        q,
        frame_id="panda_link0",
        stamp=(4, 5),
        seconds_per_point=0.05 / TRAJECTORY_JOINT_SPEED,
        msgs=RclpyMessages(),
    )
    assert trajectory == expected
    assert trajectory.points[1].time_from_start.nanosec == 100_000_000
    path = deserialize_message(node.sent[1][1], Path)
    assert path == sent.path()
    assert [p.pose.position.z for p in path.poses] == [1.0] * 7
    outputs.withdraw(session)  # type: ignore[arg-type]
    assert [topic for topic, _ in node.sent[2:]] == ["plan", "joint_trajectory"]
    assert deserialize_message(node.sent[3][1], JointTrajectory).joint_names == ["j1", "j2"]


def _check(step: int, free: bool, stage: str) -> SessionCheck:
    return SessionCheck(step, step, (0, 1), free, stage, 0.5, 0.1, False)


def test_the_check_log_and_statuses_go_out_as_bytes_of_their_messages() -> None:
    node, msgs = _Node(), RclpyMessages()
    outputs = PlannerOutputs(node)
    checks = (_check(1, True, "tree"), _check(2, False, "bisect"))
    outputs.checks(SimpleNamespace(checks=checks), (4, 5))  # type: ignore[arg-type]
    records = [CheckRecord(c.step, c.edge, c.free, c.stage, c.check_ms, c.endpoints, c.cached) for c in checks]
    assert node.sent[-1][0] == "edge_checks"
    expected = edge_checks_message(records, stamp=(4, 5), msgs=msgs)
    assert deserialize_message(node.sent[-1][1], DiagnosticArray) == expected
    outputs.status("plan", ok=False, message="no free path", values={"checks": 2, "total_s": "0.5"})
    [status] = deserialize_message(node.sent[-1][1], DiagnosticArray).status
    assert node.sent[-1][0] == "/diagnostics"
    assert status.name == "planner: plan"
    assert status.level == b"\x02"
    outputs.status("maps", ok=True, message="accepted", values={"map_version": 3}, stamp=(1, 2))
    summary = summary_status(
        ok=True,
        message="accepted",
        values={"map_version": 3},
        name="planner: maps",
        hardware_id="planner",
        msgs=msgs,
    )
    expected = diagnostics_message([summary], stamp=(1, 2), msgs=msgs)
    assert deserialize_message(node.sent[-1][1], DiagnosticArray) == expected


def test_summary_counts_checks_by_outcome_and_stage_and_gives_planning_time() -> None:
    checks = (
        _check(0, False, "probe"),
        _check(1, False, "lead"),
        _check(2, True, "tree"),
        _check(3, False, "tree"),
        _check(4, True, "bisect"),
    )
    result = SessionPlan(
        status=PlanStatus.FOUND,
        message="found",
        map_version=3,
        prior="heli",
        path_edges=(1, 3),
        checks=checks,
        seconds={"total": 0.25, "checks": 0.0015, "library": 0.125},
        stage="bisect",
        query="online",
    )
    values = plan_summary_values(
        result, {"request": "goal_pose"}, wait_s=0.01, plan_messaging_s=0.002, messaging_s=0.003
    )
    assert (values["checks"], values["free"], values["blocked"]) == (5, 2, 3)
    assert (values["probe_checks"], values["lead_checks"], values["tree_checks"], values["bisect_checks"]) == (
        1,
        1,
        2,
        1,
    )
    assert values["planning_time"] == values["total_s"] == "0.250000"
    assert (values["query"], values["stage"], values["library_s"]) == ("online", "bisect", "0.125000")
    assert values["result"] == "found"
    assert values["cause"] == ""
    assert values["request"] == "goal_pose"
    assert values["map_version"] == 3
    assert values["prior"] == "heli"
    assert values["tree"] == "heli"  # the deprecated key, kept for one release
    assert result.tree == result.prior  # the deprecated read-only alias of the field


def test_summary_reports_the_anytime_improvement_only_when_it_ran() -> None:
    checks = (_check(1, True, "tree"), _check(2, True, "improve"), _check(3, False, "improve"))
    common = {"status": PlanStatus.FOUND, "message": "found", "map_version": 1, "prior": "heli"}
    plain = plan_summary_values(
        SessionPlan(**common, checks=checks[:1], cost=751.1),  # type: ignore[arg-type]
        {"request": "goal_pose"},
        wait_s=0.0,
        plan_messaging_s=0.0,
        messaging_s=0.0,
    )
    assert not {"improvements", "improve_stop", "improve_checks", "first_cost", "cost"} & set(plain)
    improved = SessionPlan(
        **common,  # type: ignore[arg-type]
        checks=checks,
        stage="improve",
        cost=700.0,
        first_cost=751.1,
        improvements=2,
        improve_stop="optimal",
    )
    values = plan_summary_values(improved, {"request": "goal_pose"}, wait_s=0.0, plan_messaging_s=0.0, messaging_s=0.0)
    assert (values["improvements"], values["improve_stop"], values["improve_checks"]) == (2, "optimal", 2)
    assert (values["first_cost"], values["cost"]) == ("751.100000", "700.000000")
    assert list(values)[-1] == "request"  # the request's own values stay last
