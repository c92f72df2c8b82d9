"""The main job (``planner_demo``): the real node on the bundled real-scale helicopter bag, end to end."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")

from harness import use_domain

from drd_msgs_py.bags import open_bag
from drd_planner.cli.planner_demo import main
from drd_planner.ros.demo import _served_by

pytestmark = pytest.mark.slow  # nodes in child processes; several seconds each

use_domain(30)


def test_main_job_plans_prints_the_check_logs_records_and_draws(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("matplotlib", reason="the plots extra is not installed")
    # Real time: the node serves the latest request of a prior and drops an older unserved one, so a
    # loaded CI machine at 4x speed could skip a request (the real-scale online library takes ~0.6 s).
    assert main(["--out", str(tmp_path), "--rate", "1"]) == 0
    out = capsys.readouterr().out
    # The request, the replan forced by the blocking obstacle, the repeated request, then two requests
    # from where the robot has moved: a new goal, and from between two vertices.
    assert "plan 0: goal_pose on map version 2" in out
    assert "plan 1: map_update" in out
    assert "blocked by the update" in out
    assert "plan 2: goal_pose" in out
    assert out.count("check   1: edge") == 5
    assert "BLOCKED" in out
    # The stages of the check log: the tree of the real-scale prior chooses the first checks, BiSECt the rest.
    assert "[tree  ]" in out
    assert "[bisect]" in out
    served = [line for line in out.splitlines() if line.startswith("  served by:")]
    assert len(served) == 5
    assert all("precomputed DiRECt tree 'heli_lines'" in line for line in served[:3])
    assert "built online" in served[3]
    assert "off the graph" in served[4]
    assert "(1 new motions)" in out
    for k in range(5):
        png = tmp_path / f"plan_{k}.png"
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    recorded = open_bag(tmp_path / "outputs.mcap")
    topics = set(recorded.topics)
    assert {"/plan", "/edge_checks", "/diagnostics", "/checked_edges"} <= topics


def test_main_job_refuses_a_missing_bag(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--bag", str(tmp_path / "none.mcap"), "--out", str(tmp_path)]) == 2
    assert "planner_demo: error:" in capsys.readouterr().err


def _story(out: str) -> list[str]:
    """The printed plans without their times: what served each, the checks, the paths."""
    keep = ("plan ", "  served by:", "  check ", "  path:", "  -> ")
    lines = [line for line in out.splitlines() if line.startswith(keep)]
    # Times vary from run to run; everything else must not.
    return [re.sub(r"\(\d+\.\d ms\)|\d+\.\d+ ms|\s+\d+\.\d{3} ms", "T", line) for line in lines]


def test_two_demos_at_once_beside_a_cpu_hog_tell_the_same_story_on_private_domains(tmp_path: Path) -> None:
    """Issue 31 (3): no shared domain, no dependence on timing (a loaded machine once lost the replan)."""
    demo = Path(sys.executable).parent / "planner_demo"
    hog = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        runs = [
            subprocess.Popen(
                [
                    str(demo),
                    "--tree",
                    "heli_wires",
                    "--bag",
                    "heli_wires",
                    "--no-pictures",
                    "--out",
                    str(tmp_path / k),
                ],
                stdout=subprocess.PIPE,
                stderr=subprocess.STDOUT,
                text=True,
            )
            for k in ("a", "b")
        ]
        outs = [run.communicate(timeout=240)[0] for run in runs]
    finally:
        hog.kill()
        hog.wait()
    assert [run.returncode for run in runs] == [0, 0], outs
    domains = [re.search(r"ROS domain (\d+) \(private\)", out) for out in outs]
    # type: ignore[union-attr]
    assert all(domains)
    assert domains[0].group(1) != domains[1].group(1)
    stories = [_story(out) for out in outs]
    assert stories[0] == stories[1]
    assert [line.split(" on ")[0] for line in stories[0] if line.startswith("plan ")] == [
        "plan 0: goal_pose",
        "plan 1: map_update",
        "plan 2: goal_pose",
        "plan 3: goal_pose",
        "plan 4: goal_pose",
    ]


def test_served_by_names_the_probe_a_new_tree_and_a_joined_query() -> None:
    assert "probe" in _served_by("online", "probe")
    assert "no library" in _served_by("connected", "probe")
    assert "lazy search" in _served_by("online", "lead")
    assert "built online" in _served_by("online", "bisect")
    assert "off the graph" in _served_by("connected", "graph")
    assert "'heli_lines'" in _served_by("tree:heli_lines", "tree")
