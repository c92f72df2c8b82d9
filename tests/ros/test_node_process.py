"""The ``planner_node`` process: a refused parameter override ends it with one line and status 2."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")

from harness import use_domain

use_domain(70)


def test_an_override_out_of_range_ends_the_process_with_one_line_and_status_2() -> None:
    script = (
        "import sys\n"
        "from drd_planner.ros.node_process import main\n"
        "sys.exit(main(['planner_node', '--ros-args', '-p', 'goal_tolerance:=-3.0']))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120, env=dict(os.environ)
    )
    assert done.returncode == 2, done
    assert done.stderr.startswith("planner_node: error:")
    assert "goal_tolerance" in done.stderr
    assert "Traceback" not in done.stderr
