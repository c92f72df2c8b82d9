"""Tests of the checks-versus-path-cost figure (``drd_planner.bench.anytime_figure``)."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import gccd_folder

from drd_planner.bench.anytime_figure import checks_vs_cost, plot_checks_vs_cost
from drd_planner.bench.runner import run_benchmark
from drd_planner.data.gccd import load_gccd_folder


def test_more_checks_never_give_a_longer_path_and_lazysp_finds_the_shortest(tmp_path: Path) -> None:
    pytest.importorskip("matplotlib", reason="the plots extra is not installed")
    problem = load_gccd_folder(gccd_folder("dataset_xyh_1"))
    result = run_benchmark(problem, policies=("lazysp", "lazysp_posterior"), max_worlds=6, progress=False)
    data = checks_vs_cost(problem, result, seed=0)
    assert 1 <= data["worlds"] <= 6
    xs = [x for x, _ in data["anytime"]]
    ratios = [y for _, y in data["anytime"]]
    # the first path, then four budgets
    assert xs == sorted(xs)
    assert len(xs) == 5
    assert all(r >= 1.0 - 1e-9 for r in ratios)
    assert ratios[-1] <= ratios[0] + 1e-9  # the anytime step only keeps shorter verified paths
    assert set(data["policies"]) == {"lazysp", "lazysp_posterior"}
    for checks, ratio in data["policies"].values():
        # LazySP verifies the shortest free path
        assert ratio == pytest.approx(1.0)
        assert checks > 0
    files = plot_checks_vs_cost(data, problem.name, tmp_path / "c")
    assert [f.suffix for f in files] == [".png", ".svg"]
    assert all(f.stat().st_size > 1000 for f in files)
