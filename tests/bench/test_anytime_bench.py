"""The anytime benchmark: first-path and improved cost ratios, the gap reduction, budgets and its script."""

from __future__ import annotations

import dataclasses
import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO_ROOT, gccd_folder

from drd_planner.bench.anytime import anytime_markdown, anytime_prior, run_anytime_benchmark
from drd_planner.core.problem import Problem
from drd_planner.core.worlds import WorldDatabase
from drd_planner.data.planar_problem import make_planar_problem
from drd_planner.exceptions import DrdError
from drd_planner.planner.planner import Planner


@pytest.fixture(scope="module")
def problem() -> Problem:
    return make_planar_problem(model="forest", num_worlds=200, seed=5)


@pytest.fixture(scope="module")
def doc(problem: Problem) -> dict:  # type: ignore[type-arg]
    return run_anytime_benchmark(problem, Planner(anytime_prior(problem)), factors=(1.0, 3.0), progress=False)


def test_the_ratios_the_gap_and_the_budget_per_world(problem: Problem, doc: dict) -> None:  # type: ignore[type-arg]
    worlds = problem.require_worlds()
    assert doc["test_worlds"] == worlds.test_ids.size
    assert doc["no_free_path"] + doc["first_path_failed"] + doc["factors"]["1"]["episodes"] == doc["test_worlds"]
    for factor, s in doc["factors"].items():
        first, after = np.array(s["first_ratios"]), np.array(s["after_ratios"])
        assert s["episodes"] == first.size > 0
        # no path beats the world's shortest
        assert np.all(first >= 1.0 - 1e-9)
        assert np.all(after >= 1.0 - 1e-9)
        assert np.all(after <= first + 1e-12)  # improving never lengthens the path
        assert s["first_cost_ratio"] == pytest.approx(first.mean())
        before, now = first.mean(), after.mean()
        if before > 1:
            assert s["gap_reduction"] == pytest.approx(((before - 1) - (now - 1)) / (before - 1))
        checks = np.array(s["extra_checks"])
        assert s["mean_first_checks"] is not None
        assert sum(s["stops"].values()) == s["episodes"]
        assert s["reached_shortest"] == int(np.sum(after <= 1 + 1e-9))
        assert np.all(checks >= 0)
        assert float(factor) in (1.0, 3.0)
    # A bigger budget is the same first path with more checks allowed: never worse on average.
    assert doc["factors"]["3"]["after_cost_ratio"] <= doc["factors"]["1"]["after_cost_ratio"] + 1e-9
    assert doc["factors"]["1"]["improved"] >= 1


@pytest.mark.parametrize("factor", [0.5, 2.0])
def test_each_world_stays_within_its_budget(problem: Problem, factor: float) -> None:
    one = run_anytime_benchmark(problem, Planner(anytime_prior(problem)), factors=(factor,), progress=False)
    s = one["factors"][f"{factor:g}"]
    assert s["extra_checks"]
    for extra, first in zip(s["extra_checks"], s["first_checks"], strict=True):
        assert 0 <= extra <= max(1, round(factor * first))


def test_the_markdown_has_one_row_per_dataset_and_factor(doc: dict) -> None:  # type: ignore[type-arg]
    text = anytime_markdown([doc, doc])
    rows = [line for line in text.splitlines() if line.startswith(f"| {doc['dataset']} |")]
    assert len(rows) == 4
    assert "| 1x |" in rows[0]
    assert "| 3x |" in rows[1]


def test_bad_factors_and_problems_without_test_worlds_are_refused(problem: Problem) -> None:
    planner = Planner(anytime_prior(problem))
    with pytest.raises(DrdError, match="positive"):
        run_anytime_benchmark(problem, planner, factors=(0.0,), progress=False)
    with pytest.raises(DrdError, match="positive"):
        run_anytime_benchmark(problem, planner, factors=(), progress=False)
    worlds = problem.require_worlds()
    no_test = dataclasses.replace(
        problem, worlds=WorldDatabase(worlds.X, worlds.R, worlds.train_ids, np.zeros(0, dtype=np.int64))
    )
    with pytest.raises(DrdError, match="test worlds"):
        run_anytime_benchmark(no_test, planner, progress=False)


def _script() -> object:
    spec = importlib.util.spec_from_file_location(
        "bench_anytime_script", REPO_ROOT / "scripts" / "experiments" / "bench_anytime.py"
    )
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_script_reports_a_helicopter_set(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = gccd_folder("dataset_heli_canyon_1")
    out = tmp_path / "anytime.json"
    assert _script().main(["--gccd", str(folder), "--json", str(out)]) == 0  # type: ignore[attr-defined]
    printed = capsys.readouterr().out
    assert "| dataset_heli_canyon_1 | 1x |" in printed
    (saved,) = json.loads(out.read_text())
    s = saved["factors"]["1"]
    assert s["episodes"] > 50
    assert s["after_cost_ratio"] <= s["first_cost_ratio"]
