"""Tests of ``drd demo``'s library side: the story it prints for a small planar problem."""

from __future__ import annotations

import pytest

from drd_planner.bench.planar_demo import DemoOptions, run_demo


def test_the_demo_plans_the_asked_episodes_and_compares_policies(capsys: pytest.CaptureFixture[str]) -> None:
    assert run_demo(DemoOptions(worlds=60, episodes=2, seed=4)) == 0
    out = capsys.readouterr().out
    assert out.startswith("drd demo: planar 'one_wall' world model, 60 worlds, seed 4\n")
    assert out.count(" (direct_bisect):\n") == 2
    assert "  check   1: edge " in out
    assert "mean checks over " in out
    assert "oracle bound" in out
