"""Nav2's planner interface end to end: a Nav2-style client in another process (tests/ros/nav2_client.py).

The client imports only rclpy and the standard packages (``nav2_msgs`` included, no drd_planner) and runs
against a real planner node in this process, over DDS on a domain of this test: a plan (path, planning
time, error code NONE), a failure with its code (a goal outside the map: GOAL_OUTSIDE_MAP; an unknown
planner_id: INVALID_PLANNER), ``is_path_valid`` before and after a map that blocks the path, and a cancel
in the middle of a long plan (every collision check made slow here) that stops it between two checks.
"""

from __future__ import annotations

import json
import os
import queue
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

rclpy = pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")
pytest.importorskip("nav2_msgs.action", reason="nav2_msgs not importable (scripts/tools/build_nav2_msgs.sh)")

from harness import Peer, active_planner, private_context, spin_until  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402

from drd_msgs_py.factory import RclpyMessages  # noqa: E402
from drd_planner.domains.helicopter import HelicopterDomain  # noqa: E402
from drd_planner.geometry.pose import Pose  # noqa: E402
from drd_planner.geometry.shapes import Box  # noqa: E402
from drd_planner.planning.world_messages import helicopter_world_messages, obstacle_markers  # noqa: E402
from drd_planner.ros.nav2_host import Nav2Host, nav2_interfaces  # noqa: E402
from drd_planner.ros.node import PlannerNode  # noqa: E402

pytestmark = pytest.mark.slow
TREE = Path(__file__).resolve().parents[2] / "trees" / "heli_wires.npz"
CLIENT = Path(__file__).resolve().parent / "nav2_client.py"
#: Seconds each collision check takes once the test makes checks slow (the cancel step's long plan).
SLOW_CHECK_S = 0.2
DOMAIN = 181 + os.getpid() % 9  # this helper's domains: 181-189

os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ["ROS_DOMAIN_ID"] = str(DOMAIN)


class SlowChecker:
    """A checker that sleeps :data:`SLOW_CHECK_S` before each check (a slow map), then asks the real one."""

    def __init__(self, real: Any, log: list[float]) -> None:
        self._real = real
        self._log = log

    def check(self, edge: int) -> bool:
        time.sleep(SLOW_CHECK_S)
        self._log.append(time.monotonic())
        return bool(self._real.check(edge))

    def check_motion(self, states: Any) -> bool:
        time.sleep(SLOW_CHECK_S)
        self._log.append(time.monotonic())
        return bool(self._real.check_motion(states))

    def __getattr__(self, name: str) -> Any:
        return getattr(self._real, name)


@pytest.fixture
def context() -> Iterator[Any]:
    with private_context() as ctx:
        yield ctx


def _lines(process: subprocess.Popen[str]) -> queue.Queue[str]:
    """The client's stdout lines, read by a thread (the test spins its executor meanwhile)."""
    lines: queue.Queue[str] = queue.Queue()

    def read() -> None:
        assert process.stdout is not None
        for line in process.stdout:
            lines.put(line)

    threading.Thread(target=read, daemon=True).start()
    return lines


def _next(executor: Any, lines: queue.Queue[str], process: subprocess.Popen[str], timeout: float = 90.0) -> Any:
    """Spin until the client's next JSON line (its steps need the node's maps and plans)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        executor.spin_once(timeout_sec=0.02)
        try:
            return json.loads(lines.get_nowait())
        except queue.Empty:
            if process.poll() is not None and lines.empty():
                assert process.stderr is not None
                raise AssertionError(f"the client ended: {process.stderr.read()[-3000:]}") from None
    raise AssertionError("no line from the client in time")


def test_a_nav2_client_plans_fails_with_codes_asks_validity_and_cancels(
    context: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    assert nav2_interfaces()[0].Result.GOAL_OUTSIDE_MAP == 204
    params = [
        Parameter("prior_paths", value=[str(TREE)]),
        Parameter("start_without_robot_state", value="prior_start"),
        Parameter("replan_on_map_update", value=False),  # the cancel step's plan is the first on the new map
    ]
    node = PlannerNode(context=context, parameter_overrides=params)
    peer = Peer(context)
    with active_planner(context, node, peer) as executor:
        assert isinstance(node._nav2, Nav2Host)
        session = node.sessions[0]
        domain = session.domain
        assert isinstance(domain, HelicopterDomain)
        markers, cloud = helicopter_world_messages(
            domain.make_world("wires", 3), wire_segments=8, frame_id="map", msgs=RclpyMessages()
        )
        peer.terrain.publish(cloud)
        peer.obstacles.publish(markers)
        assert spin_until(executor, lambda: node.snapshot.version >= 2)
        slow = threading.Event()
        checks: list[float] = []
        real = session.checker
        monkeypatch.setattr(
            session, "checker", lambda snap: SlowChecker(real(snap), checks) if slow.is_set() else real(snap)
        )

        goal = [float(v) for v in session.goal_state[:3]]
        scenario = {"goal": goal, "far": [1e5, 0.0, 65.0], "cancel_after_s": 3 * SLOW_CHECK_S}
        process = subprocess.Popen(
            [sys.executable, str(CLIENT), json.dumps(scenario)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=dict(os.environ),
        )
        try:
            lines = _lines(process)
            plan = _next(executor, lines, process)
            # SUCCEEDED, NONE
            assert plan["step"] == "plan"
            assert plan["status"] == 4
            assert plan["error_code"] == 0
            assert plan["poses"] > 10
            assert plan["frame"] == "map"
            assert plan["planning_time"] > 0
            assert plan["last"] == pytest.approx(goal, abs=1e-6)
            outside = _next(executor, lines, process)
            assert (outside["status"], outside["error_code"]) == (6, 204)  # ABORTED, GOAL_OUTSIDE_MAP
            assert "outside the lattice" in outside["error_msg"]
            assert _next(executor, lines, process) == {"step": "planner_id", "status": 6, "error_code": 201}
            assert _next(executor, lines, process) == {
                "step": "valid_before",
                "is_valid": True,
                "invalid": [],
            }

            block = _next(executor, lines, process)
            version = node.snapshot.version
            box = [("blocking/1", Box((30.0, 30.0, 30.0)), Pose(position=tuple(block["at"])))]
            peer.obstacles.publish(obstacle_markers(box, frame_id="map", msgs=RclpyMessages(), delete_all_first=False))
            assert spin_until(executor, lambda: node.snapshot.version > version)
            slow.set()
            assert process.stdin is not None
            process.stdin.write("blocked\n")
            process.stdin.flush()
            after = _next(executor, lines, process)
            assert after["step"] == "valid_after"
            assert not after["is_valid"]
            assert after["invalid"]

            published = len(peer.plans)
            begun = len(checks)
            cancel = _next(executor, lines, process)
            # CANCELED
            assert cancel["step"] == "cancel"
            assert cancel["status"] == 5
            assert cancel["poses"] == 0
            assert cancel["seconds"] < 2.0
            assert "canceled" in cancel["error_msg"]
            made = len(checks) - begun
            assert 1 <= made <= 8, made  # stopped between checks, long before its end
            assert _next(executor, lines, process) == {"step": "imports", "drd": []}
            assert process.wait(timeout=30) == 0
        finally:
            if process.poll() is None:
                process.kill()
        slow.clear()
        time.sleep(0.5)
        assert len(checks) == begun + made  # no check after the cancel
        assert len(peer.plans) == published  # the cancelled plan published nothing
        assert not [e for e in node.errors if "internal error" in e], node.errors


def test_without_nav2_msgs_the_node_runs_without_the_interface_and_says_why(
    context: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    from drd_planner.ros import nav2_host

    def missing() -> tuple[Any, Any]:
        raise ImportError("No module named 'nav2_msgs'")

    monkeypatch.setattr(nav2_host, "nav2_interfaces", missing)
    node = PlannerNode(context=context, parameter_overrides=[Parameter("prior_paths", value=[str(TREE)])])
    peer = Peer(context)
    with active_planner(context, node, peer):
        assert node._nav2 is None
        names = [name for name, _ in node.get_service_names_and_types()]
        assert "/get_plan" in names
        assert "/is_path_valid" not in names
