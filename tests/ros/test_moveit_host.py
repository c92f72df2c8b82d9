"""MoveIt's interface end to end: a MoveIt-style client in another process (tests/ros/moveit_client.py).

The client imports only rclpy and the standard packages (``moveit_msgs`` included, no drd_planner) and runs
against a real planner node with the arm prior in this process, over DDS on a domain of this test: it
publishes a full planning scene whose box blocks the straight joint motion from start to goal, calls
``plan_kinematic_path`` with a start state and joint goal constraints, and gets a timed trajectory from that
start to that goal whose every segment the arm's own checker finds free on that scene (and the straight
motion it avoided blocked); a position goal is INVALID_GOAL_CONSTRAINTS (no inverse kinematics); a scene
with an octomap is refused with its reason, the maps unchanged; a diff adding a box at the goal makes the same
request GOAL_IN_COLLISION.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import queue
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

rclpy = pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")
pytest.importorskip("moveit_msgs.srv", reason="moveit_msgs not importable (scripts/tools/build_moveit_msgs.sh)")

from harness import Peer, active_planner, private_context, spin_until  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402

from drd_planner.domains.arm import default_panda_dir  # noqa: E402
from drd_planner.geometry.pose import Pose  # noqa: E402
from drd_planner.geometry.shapes import Box  # noqa: E402
from drd_planner.planning.map_state import MapSnapshot  # noqa: E402
from drd_planner.ros.moveit_host import MoveItHost, duration_of, moveit_interfaces  # noqa: E402
from drd_planner.ros.node import PlannerNode  # noqa: E402

pytestmark = pytest.mark.slow
TREE = Path(__file__).resolve().parents[2] / "trees" / "arm_table_clutter.npz"
CLIENT = Path(__file__).resolve().parent / "moveit_client.py"
FRAME = "panda_link0"
BOX_M = 0.12  # the blocking box's edge, metres
DOMAIN = 191 + os.getpid() % 9  # this helper's domains: 191-199

os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ["ROS_DOMAIN_ID"] = str(DOMAIN)


@pytest.fixture
def context() -> Iterator[Any]:
    with private_context() as ctx:
        yield ctx


def _dense(states: Any, step: float) -> Any:
    """The waypoints with samples between them no further apart than ``step`` (rad) per joint."""
    q = np.asarray(states, dtype=np.float64)
    rows = [q[:1]]
    for a, b in itertools.pairwise(q):
        n = max(1, math.ceil(float(np.max(np.abs(b - a))) / step))
        rows.append(a + (b - a) * (np.arange(1, n + 1)[:, None] / n))
    return np.concatenate(rows)


def _blocking_box(session: Any, start: Any, goal: Any) -> tuple[Any, Any]:
    """A box at the end effector part-way along the straight motion that blocks it but neither end."""
    step = session.domain.resolution
    straight = _dense([start, goal], step)
    for fraction in (0.5, 0.4, 0.6, 0.3, 0.7):
        q = start + fraction * (goal - start)
        center = session.positions(q[None, :])[0]
        box = ((Box((BOX_M, BOX_M, BOX_M)), Pose(position=tuple(float(v) for v in center))),)
        snapshot = MapSnapshot(0).with_obstacles({"moveit:blocker": box})
        checker = session.checker(snapshot)
        ends_free = checker.check_motion(start[None, :]) and checker.check_motion(goal[None, :])
        if ends_free and not checker.check_motion(straight):
            return center, checker
    raise AssertionError("no box blocks the straight motion without blocking an end")


def _lines(process: subprocess.Popen[str]) -> queue.Queue[str]:
    lines: queue.Queue[str] = queue.Queue()

    def read() -> None:
        assert process.stdout is not None
        for line in process.stdout:
            lines.put(line)

    threading.Thread(target=read, daemon=True).start()
    return lines


def _next(executor: Any, lines: queue.Queue[str], process: subprocess.Popen[str], timeout: float = 180.0) -> Any:
    """Spin until the client's next JSON line."""
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


def _say(process: subprocess.Popen[str], text: str) -> None:
    assert process.stdin is not None
    process.stdin.write(text + "\n")
    process.stdin.flush()


def test_duration_of_splits_seconds() -> None:
    d = duration_of(2.25)
    assert (d.sec, d.nanosec) == (2, 250_000_000)
    assert (duration_of(-1.0).sec, duration_of(-1.0).nanosec) == (0, 0)


@pytest.mark.skipif(not default_panda_dir().is_dir(), reason="Panda model not found")
def test_a_moveit_client_sends_a_scene_and_gets_a_trajectory_checked_free_on_it(context: Any) -> None:
    assert moveit_interfaces()[1].Response().motion_plan_response.error_code.SUCCESS == 1
    params = [
        Parameter("prior_paths", value=[str(TREE)]),
        Parameter("frame_id", value=FRAME),
        Parameter("start_without_robot_state", value="prior_start"),
    ]
    node = PlannerNode(context=context, parameter_overrides=params)
    peer = Peer(context)
    with active_planner(context, node, peer) as executor:
        assert isinstance(node._moveit, MoveItHost)
        session = node.sessions[0]
        start = session.vertex_state(int(session.domain.start))
        goal = session.goal_state
        center, checker = _blocking_box(session, start, goal)
        scenario = {
            "frame": FRAME,
            "joints": list(session.joint_names),
            "start": start.tolist(),
            "goal": goal.tolist(),
            "box": {"center": center.tolist(), "size": [BOX_M] * 3},
            "goal_box": {"center": session.positions(goal[None, :])[0].tolist(), "size": [BOX_M] * 3},
        }
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
            assert _next(executor, lines, process) == {"step": "scene"}
            assert spin_until(executor, lambda: "moveit:blocker" in node.snapshot.obstacles, timeout=60)
            version = node.snapshot.version
            _say(process, "applied")

            plan = _next(executor, lines, process)
            assert plan["step"] == "plan", plan["message"]
            assert plan["code"] == 1, plan["message"]  # SUCCESS
            assert plan["joints"] == list(session.joint_names)
            points = np.array(plan["points"])
            np.testing.assert_allclose(points[0], start, atol=1e-9)
            np.testing.assert_allclose(points[-1], goal, atol=1e-9)
            assert np.all(np.diff(plan["times"]) > 0)
            assert plan["times"][0] == 0.0
            assert plan["planning_time"] > 0
            # every edge checked free on that scene, by the arm's own checker, and not the blocked straight line
            assert checker.check_motion(_dense(points, session.domain.resolution))
            assert len(points) > 2

            position = _next(executor, lines, process)
            assert position["code"] == -16
            assert "inverse kinematics" in position["message"]

            assert _next(executor, lines, process) == {"step": "octomap"}
            assert spin_until(executor, lambda: any("octomaps are not supported" in e for e in node.errors), 60)
            assert node.snapshot.version == version  # the maps unchanged
            _say(process, "refused")

            assert _next(executor, lines, process) == {"step": "diff"}
            assert spin_until(
                executor, lambda: {"moveit:blocker", "moveit:at_goal"} <= set(node.snapshot.obstacles), 60
            )
            _say(process, "applied")
            blocked = _next(executor, lines, process)
            assert (blocked["code"], blocked["points"]) == (-12, 0), blocked  # GOAL_IN_COLLISION, no trajectory
            assert _next(executor, lines, process) == {"step": "imports", "drd": []}
            assert process.wait(timeout=30) == 0
        finally:
            if process.poll() is None:
                process.kill()
        assert not [e for e in node.errors if "internal error" in e], node.errors


def test_without_moveit_msgs_the_node_runs_without_the_interface(context: Any, monkeypatch: pytest.MonkeyPatch) -> None:
    from drd_planner.ros import moveit_host

    def missing() -> tuple[Any, Any]:
        raise ImportError("No module named 'moveit_msgs'")

    monkeypatch.setattr(moveit_host, "moveit_interfaces", missing)
    node = PlannerNode(context=context, parameter_overrides=[Parameter("prior_paths", value=[str(TREE)])])
    peer = Peer(context)
    with active_planner(context, node, peer):
        assert node._moveit is None
        names = [name for name, _ in node.get_service_names_and_types()]
        assert "/get_plan" in names
        assert "/plan_kinematic_path" not in names
