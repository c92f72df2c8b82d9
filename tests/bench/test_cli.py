"""Tests of the ``drd`` command line (in-process) and the benchmark runner's JSON and table."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import gccd_folder

from drd_planner import __version__
from drd_planner.bench.runner import (
    BenchmarkResult,
    PolicyStats,
    benchmark_json,
    markdown_table,
    run_benchmark,
)
from drd_planner.cli import main
from drd_planner.data.gccd import load_gccd_folder
from drd_planner.data.tree_file import load_tree

POLICY_KEYS = {"mean_checks", "median_checks", "checks", "failures", "mean_select_ms"}
DOC_KEYS = {"dataset", "test_ids", "oracle_lower_bound", "policies"}
DEFAULT_POLICIES = ["direct_bisect", "direct_only", "bisect", "bisect_all"]


@pytest.fixture(scope="module")
def d2d1() -> Path:
    return gccd_folder("dataset_2d_1")


@pytest.fixture(scope="module")
def tree_2d1(d2d1: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("trees") / "t.npz"
    assert main(["build-tree", "--gccd", str(d2d1), "--out", str(out)]) == 0
    return out


def _one_error_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("drd: error:"), err
    return lines[0]


def test_bench_writes_design_json(d2d1: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out.json"
    assert main(["bench", "--gccd", str(d2d1), "--max-worlds", "5", "--json", str(out)]) == 0
    captured = capsys.readouterr()
    assert "| dataset_2d_1 |" in captured.out
    assert f"wrote {out}" in captured.out
    doc = json.loads(out.read_text())
    # DESIGN.md section 5 keys, plus only the runner's documented "tree" block.
    assert DOC_KEYS <= set(doc)
    assert set(doc) - DOC_KEYS <= {"tree"}
    assert doc["dataset"] == "dataset_2d_1"
    test_ids = doc["test_ids"]
    assert len(test_ids) == 5
    assert all(isinstance(t, int) for t in test_ids)
    problem = load_gccd_folder(d2d1)
    worlds = problem.require_worlds()
    assert test_ids == worlds.test_ids[:5].tolist()
    lb = doc["oracle_lower_bound"]
    assert set(lb) == {"mean", "per_world"}
    assert len(lb["per_world"]) == 5
    assert all(isinstance(v, float) for v in lb["per_world"])
    assert lb["mean"] == pytest.approx(sum(lb["per_world"]) / 5)
    assert set(doc["policies"]) == set(DEFAULT_POLICIES)
    for name, stats in doc["policies"].items():
        assert set(stats) == POLICY_KEYS, name
        checks = stats["checks"]
        assert len(checks) == 5
        assert all(isinstance(c, int) for c in checks)
        assert stats["mean_checks"] == pytest.approx(sum(checks) / 5)
        assert stats["median_checks"] == pytest.approx(sorted(checks)[2])
        assert isinstance(stats["failures"], int)
        assert 0 <= stats["failures"] <= 5
        assert stats["mean_select_ms"] >= 0
        for c, bound in zip(checks, lb["per_world"], strict=True):
            assert c >= bound, (name, checks, lb["per_world"])


def test_bench_markdown_and_policy_subset(
    d2d1: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    md = tmp_path / "table.md"
    out = tmp_path / "o.json"
    argv = ["bench", "--gccd", str(d2d1), "--max-worlds", "3", "--policies", "bisect,bisect_all"]
    assert main([*argv, "--markdown", str(md), "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    table = md.read_text()
    assert table in printed
    assert table.splitlines()[0] == "| dataset | bisect | bisect_all | oracle bound |"
    doc = json.loads(out.read_text())
    assert list(doc["policies"]) == ["bisect", "bisect_all"]
    assert doc["tree"] == {}


def test_build_tree_then_plan(d2d1: Path, tree_2d1: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bundle = load_tree(tree_2d1, expected_domain="gccd")
    assert bundle.problem.num_edges == 923
    assert bundle.problem.num_paths == 500
    assert bundle.provenance["dataset"] == "dataset_2d_1"
    world = int(load_gccd_folder(d2d1).require_worlds().test_ids[0])
    capsys.readouterr()
    assert main(["plan", "--tree", str(tree_2d1), "--gccd", str(d2d1), "--world", str(world)]) == 0
    out = capsys.readouterr().out
    assert "check   1:" in out
    assert "verified free after" in out
    assert "[tree]" in out


@pytest.mark.parametrize("policy", ["direct_only", "bisect", "bisect_all"])
def test_plan_with_other_policies(
    d2d1: Path, tree_2d1: Path, policy: str, capsys: pytest.CaptureFixture[str]
) -> None:
    world = int(load_gccd_folder(d2d1).require_worlds().test_ids[1])
    argv = ["plan", "--tree", str(tree_2d1), "--gccd", str(d2d1), "--world", str(world), "--policy", policy]
    rc = main(argv)
    out = capsys.readouterr().out
    assert rc in (0, 1)
    assert ("verified free after" in out) == (rc == 0)


def test_plan_world_out_of_range(d2d1: Path, tree_2d1: Path, capsys: pytest.CaptureFixture[str]) -> None:
    capsys.readouterr()
    assert main(["plan", "--tree", str(tree_2d1), "--gccd", str(d2d1), "--world", "1000"]) == 2
    assert "--world" in _one_error_line(capsys.readouterr().err)


def test_bench_with_saved_tree(
    d2d1: Path, tree_2d1: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "o.json"
    argv = ["bench", "--gccd", str(d2d1), "--tree", str(tree_2d1), "--max-worlds", "3", "--json", str(out)]
    assert main(argv) == 0
    doc = json.loads(out.read_text())
    bundle = load_tree(tree_2d1)
    assert doc["tree"]["nodes"] == bundle.tree.num_nodes
    for stats in doc["policies"].values():
        assert len(stats["checks"]) == 3


@pytest.mark.parametrize("command", ["plan", "bench"])
def test_tree_for_another_dataset_is_refused(
    tree_2d1: Path, command: str, capsys: pytest.CaptureFixture[str]
) -> None:
    other = gccd_folder("dataset_2d_4")
    argv = [command, "--tree", str(tree_2d1), "--gccd", str(other)]
    argv += ["--world", "0"] if command == "plan" else ["--max-worlds", "1"]
    capsys.readouterr()
    assert main(argv) == 2
    captured = capsys.readouterr()
    line = _one_error_line(captured.err)
    assert "another" in line
    assert "verified" not in captured.out


def test_tree_for_same_sized_dataset_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    d2, d3 = gccd_folder("dataset_2d_2"), gccd_folder("dataset_2d_3")
    tree = tmp_path / "t2.npz"
    assert main(["build-tree", "--gccd", str(d2), "--out", str(tree)]) == 0
    capsys.readouterr()
    assert main(["plan", "--tree", str(tree), "--gccd", str(d3), "--world", "0"]) == 2


def test_missing_folder_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "--gccd", str(tmp_path / "nope")]) == 2
    captured = capsys.readouterr()
    assert "nope" in _one_error_line(captured.err)
    assert captured.out == ""


def test_missing_tree_file_exits_2(d2d1: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["plan", "--tree", str(tmp_path / "none.npz"), "--gccd", str(d2d1), "--world", "0"]
    assert main(argv) == 2
    assert "none.npz" in _one_error_line(capsys.readouterr().err)


def test_corrupt_tree_file_exits_2(d2d1: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"PK\x03\x04 definitely not a tree")
    assert main(["bench", "--gccd", str(d2d1), "--tree", str(bad)]) == 2
    _one_error_line(capsys.readouterr().err)


def test_unknown_policy_exits_2(d2d1: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "--gccd", str(d2d1), "--policies", "bisect,no_such_policy"]) == 2
    captured = capsys.readouterr()
    assert "no_such_policy" in _one_error_line(captured.err)
    assert captured.out == ""


def test_unknown_plan_policy_is_a_usage_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["plan", "--tree", "t.npz", "--gccd", str(tmp_path), "--world", "0", "--policy", "nope"]
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    assert "nope" in capsys.readouterr().err


def test_no_command_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main([])
    assert info.value.code == 2
    assert "usage: drd" in capsys.readouterr().err


def test_demo(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["demo", "--worlds", "150", "--episodes", "1"]) == 0
    out = capsys.readouterr().out
    assert "mean checks" in out
    assert "DiRECt tree:" in out
    assert out.count("test world ") == 1
    assert "verified free after" in out or "no_free_path" in out


def test_version_in_process(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.strip() == f"drd_planner {__version__}"


def test_console_script_version() -> None:
    exe = shutil.which("drd")
    if exe is None:
        pytest.skip("the drd console script is not installed on PATH")
    proc = subprocess.run([exe, "--version"], capture_output=True, text=True, timeout=60, check=False)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == f"drd_planner {__version__}"


def test_module_entry_point_reports_errors() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "drd_planner.cli", "bench", "--gccd", "/nonexistent/drd/folder"],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert proc.returncode == 2
    assert proc.stdout == ""
    _one_error_line(proc.stderr)


# --------------------------------------------------------------------------------------------------
# Runner pieces without a dataset
# --------------------------------------------------------------------------------------------------


def _result(
    name: str, checks: dict[str, list[int]], failures: dict[str, int], lb: list[float]
) -> BenchmarkResult:
    stats = {p: PolicyStats(c, failures.get(p, 0), [0.1] * len(c), 0.0) for p, c in checks.items()}
    return BenchmarkResult(name, list(range(len(lb))), lb, stats)


def test_markdown_table() -> None:
    a = _result("ds_a", {"bisect": [4, 6], "direct_bisect": [3, 4]}, {"bisect": 1}, [3.0, 4.0])
    b = _result("ds_b", {"bisect": [10, 12]}, {}, [float("nan"), 8.0])
    table = markdown_table([a, b], ["direct_bisect", "bisect"])
    assert table.endswith("\n")
    assert table.splitlines() == [
        "| dataset | direct_bisect | bisect | oracle bound |",
        "|---|---|---|---|",
        "| ds_a | 3.50 | 5.00 (1 failed) | 3.50 |",
        "| ds_b | — | 11.00 | 8.00 |",
    ]


def test_markdown_table_without_results() -> None:
    assert markdown_table([], ["bisect"]) == "| dataset | bisect | oracle bound |\n|---|---|---|\n"


def test_benchmark_json_maps_nan_bounds_to_null() -> None:
    res = _result("ds", {"bisect": [5, 7, 9]}, {"bisect": 0}, [3.0, float("nan"), 5.0])
    doc = benchmark_json(res)
    assert doc["oracle_lower_bound"]["per_world"] == [3.0, None, 5.0]
    assert doc["oracle_lower_bound"]["mean"] == pytest.approx(4.0)
    assert doc["policies"]["bisect"] == {
        "mean_checks": 7.0,
        "median_checks": 7.0,
        "checks": [5, 7, 9],
        "failures": 0,
        "mean_select_ms": pytest.approx(0.1),
    }
    json.dumps(doc, allow_nan=False)


def test_run_benchmark_on_a_planar_problem() -> None:
    from drd_planner.domains.planar import make_planar_problem

    problem = make_planar_problem(num_worlds=100, max_paths=30, seed=1)
    res = run_benchmark(problem, policies=["bisect", "direct_bisect"], seed=0, max_worlds=4, progress=False)
    assert res.test_ids == problem.require_worlds().test_ids[:4].tolist()
    assert res.tree_info["nodes"] >= 1
    for stats in res.policies.values():
        assert len(stats.checks) == 4
        for c, bound in zip(stats.checks, res.lower_bound, strict=True):
            if not math.isnan(bound):
                assert c >= bound
