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
    DEFAULT_POLICIES,
    BenchmarkResult,
    PolicyStats,
    benchmark_json,
    markdown_table,
    run_benchmark,
)
from drd_planner.cli.main import main
from drd_planner.core.region_rule import REGION_RULES
from drd_planner.data.gccd import load_gccd_folder
from drd_planner.planner import load_prior, load_tree_bundle

POLICY_KEYS = {"mean_checks", "median_checks", "checks", "failures", "mean_select_ms"}
DOC_KEYS = {"dataset", "test_ids", "oracle_lower_bound", "policies"}
#: Keys the runner adds to the ``drd bench --json`` document of docs/getting-started.md (documented in
#: bench/runner.py and bench/suite.py).
EXTRA_DOC_KEYS = {
    "tree",
    "settings",
    "relative_protocol",
    "wall_seconds",
    "notes",
    "figures",
    "training_curve",
}
EXTRA_POLICY_KEYS = {"relative", "failed_worlds"}


@pytest.fixture(scope="module")
def d2d1() -> Path:
    return gccd_folder("dataset_2d_1")


@pytest.fixture(scope="module")
def tree_2d1(d2d1: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    # The paper's setting, so that the tree is walked (a validated eta may switch at the root).
    out = tmp_path_factory.mktemp("trees") / "t.npz"
    assert main(["build-tree", "--gccd", str(d2d1), "--out", str(out), "--eta", "0.2", "--kappa", "none"]) == 0
    return out


def test_build_tree_validates_eta_and_kappa_on_random_queries(
    d2d1: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "v.npz"
    assert main(["build-tree", "--gccd", str(d2d1), "--out", str(out), "--kappa", "none"]) == 0
    printed = capsys.readouterr().out
    # --region-rule auto validates both
    assert "random queries" in printed
    assert "region rule" in printed
    prior = load_tree_bundle(out)
    assert "random queries" in prior.provenance["eta"]
    assert prior.pseudo_count is None
    whole = load_prior(out)
    assert whole.region_rule in REGION_RULES
    assert f"region rule {whole.region_rule}" in prior.provenance["eta"]
    assert whole.trees[0].tree.region_rule in REGION_RULES
    # A given rule is stored as given, for the prior's new queries and the dataset's own tree.
    fixed = tmp_path / "f.npz"
    argv = ["build-tree", "--gccd", str(d2d1), "--out", str(fixed), "--eta", "0.2", "--kappa", "none"]
    assert main([*argv, "--region-rule", "per_check"]) == 0
    capsys.readouterr()
    given = load_prior(fixed)
    assert given.region_rule == "per_check"
    assert given.trees[0].tree.region_rule == "per_check"


def test_build_tree_says_when_eta_1_leaves_the_tree_unused(
    d2d1: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 33 item 10: eta 1 means BiSECt from the first check; the output says so and what would help."""
    argv = ["build-tree", "--gccd", str(d2d1), "--kappa", "none"]
    assert main([*argv, "--out", str(tmp_path / "one.npz"), "--eta", "1"]) == 0
    printed = capsys.readouterr().out
    assert "this query's DiRECt tree is never used" in printed
    assert "more worlds (now " in printed
    assert main([*argv, "--out", str(tmp_path / "used.npz"), "--eta", "0.2"]) == 0
    assert "never used" not in capsys.readouterr().out


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
    # The documented keys (docs/getting-started.md, drd bench --json), plus only the runner's extra blocks.
    assert DOC_KEYS <= set(doc)
    assert set(doc) - DOC_KEYS <= EXTRA_DOC_KEYS
    assert doc["dataset"] == "dataset_2d_1"
    test_ids = doc["test_ids"]
    assert len(test_ids) == 5
    assert all(isinstance(t, int) for t in test_ids)
    problem = load_gccd_folder(d2d1)
    worlds = problem.require_worlds()
    assert test_ids == worlds.test_ids[:5].tolist()
    lb = doc["oracle_lower_bound"]
    assert set(lb) == {"mean", "per_world", "relative"}
    assert len(lb["per_world"]) == 5
    assert all(isinstance(v, float) for v in lb["per_world"])
    assert lb["mean"] == pytest.approx(sum(lb["per_world"]) / 5)
    assert set(doc["policies"]) == set(DEFAULT_POLICIES)
    assert doc["relative_protocol"]["reference"] == "direct_bisect"
    for name, stats in doc["policies"].items():
        assert set(stats) == POLICY_KEYS | EXTRA_POLICY_KEYS, name
        rel = stats["relative"]
        assert len(rel["per_world"]) == 5
        assert rel["unfiltered"]["n"] == 5
        assert rel["filtered"]["n"] == doc["relative_protocol"]["num_kept"]
        checks = stats["checks"]
        assert len(checks) == 5
        assert all(isinstance(c, int) for c in checks)
        assert stats["mean_checks"] == pytest.approx(sum(checks) / 5)
        assert stats["median_checks"] == pytest.approx(sorted(checks)[2])
        assert isinstance(stats["failures"], int)
        assert 0 <= stats["failures"] <= 5
        assert stats["mean_select_ms"] >= 0
        assert len(stats["failed_worlds"]) == stats["failures"]
        for k, (c, bound) in enumerate(zip(checks, lb["per_world"], strict=True)):
            # A proven library path costs at least the bound (full-graph lazysp may prove another path).
            if k not in stats["failed_worlds"] and name != "lazysp":
                assert c >= bound, (name, checks, lb["per_world"])
    ref = doc["policies"]["direct_bisect"]["checks"]
    for name, stats in doc["policies"].items():
        expect = [(c - r) / r for c, r in zip(stats["checks"], ref, strict=True)]
        assert stats["relative"]["per_world"] == pytest.approx(expect), name


def test_bench_markdown_and_policy_subset(d2d1: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    md = tmp_path / "table.md"
    out = tmp_path / "o.json"
    argv = ["bench", "--gccd", str(d2d1), "--max-worlds", "3", "--policies", "bisect,bisect_all"]
    assert main([*argv, "--markdown", str(md), "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    report = md.read_text()
    assert report in printed
    lines = report.splitlines()
    assert "| dataset | bisect | bisect_all | oracle bound |" in lines
    # Without the reference the Table-1 rows are dashes.
    assert "| dataset_2d_1 | 3 | — | — |" in lines
    doc = json.loads(out.read_text())
    assert list(doc["policies"]) == ["bisect", "bisect_all"]
    assert doc["tree"] == {}
    assert doc["relative_protocol"] is None
    assert all(p["relative"] is None for p in doc["policies"].values())


def test_build_tree_then_plan(d2d1: Path, tree_2d1: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bundle = load_tree_bundle(tree_2d1, expected_domain="gccd")
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


@pytest.mark.parametrize("policy", ["bisect", "bisect_all", "lazysp_set", "mvoi"])
def test_plan_with_other_policies(d2d1: Path, tree_2d1: Path, policy: str, capsys: pytest.CaptureFixture[str]) -> None:
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


def test_bench_with_saved_tree(d2d1: Path, tree_2d1: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "o.json"
    argv = ["bench", "--gccd", str(d2d1), "--prior", str(tree_2d1), "--max-worlds", "3", "--json", str(out)]
    assert main(argv) == 0
    doc = json.loads(out.read_text())
    bundle = load_tree_bundle(tree_2d1)
    assert doc["tree"]["nodes"] == bundle.tree.num_nodes
    for stats in doc["policies"].values():
        assert len(stats["checks"]) == 3


@pytest.mark.parametrize("command", ["plan", "bench"])
def test_tree_for_another_dataset_is_refused(tree_2d1: Path, command: str, capsys: pytest.CaptureFixture[str]) -> None:
    other = gccd_folder("dataset_2d_4")
    argv = [command, "--prior", str(tree_2d1), "--gccd", str(other)]
    argv += ["--world", "0"] if command == "plan" else ["--max-worlds", "1"]
    capsys.readouterr()
    assert main(argv) == 2
    captured = capsys.readouterr()
    line = _one_error_line(captured.err)
    assert "another" in line
    assert "verified" not in captured.out


def test_prior_of_the_same_graph_plans_with_a_note(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # dataset_2d_2 and dataset_2d_3 share their graph: a prior of one plans on the other's worlds (every
    # check is still made on that world), and says that the prior came from elsewhere.
    d2, d3 = gccd_folder("dataset_2d_2"), gccd_folder("dataset_2d_3")
    prior = tmp_path / "t2.npz"
    assert main(["build-tree", "--gccd", str(d2), "--out", str(prior), "--eta", "0.2", "--kappa", "none"]) == 0
    capsys.readouterr()
    world = int(load_gccd_folder(d3).require_worlds().test_ids[0])
    assert main(["plan", "--tree", str(prior), "--gccd", str(d3), "--world", str(world)]) == 0
    out = capsys.readouterr().out
    assert "prior was built from dataset_2d_2" in out
    assert "query tree:dataset_2d_2" in out  # same start and goal: the precomputed tree serves it


def test_prior_of_another_graph_is_refused(d2d1: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    prior = tmp_path / "t2.npz"
    assert (
        main(
            [
                "build-tree",
                "--gccd",
                str(gccd_folder("dataset_2d_2")),
                "--out",
                str(prior),
                "--eta",
                "0.2",
                "--kappa",
                "none",
            ]
        )
        == 0
    )
    capsys.readouterr()
    assert main(["plan", "--tree", str(prior), "--gccd", str(d2d1), "--world", "0"]) == 2
    assert "another graph" in _one_error_line(capsys.readouterr().err)


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
    assert main(["bench", "--gccd", str(d2d1), "--prior", str(bad)]) == 2
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
    assert "verified free after" in out or "no_path" in out


def test_version_in_process(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.strip() == f"drd_planner {__version__}"


def console_script(name: str) -> Path | None:
    """An installed console script: next to this interpreter (a venv's bin, as in CI), else on PATH."""
    beside = Path(sys.executable).parent / name  # not resolved: a venv's python is a link out of it
    if beside.is_file():
        return beside
    found = shutil.which(name)
    return None if found is None else Path(found)


def test_console_script_version() -> None:
    exe = console_script("drd")
    if exe is None:
        pytest.skip("the drd console script is neither beside the interpreter nor on PATH")
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


def _result(name: str, checks: dict[str, list[int]], failures: dict[str, int], lb: list[float]) -> BenchmarkResult:
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
        "failed_worlds": [],
        "relative": None,  # no direct_bisect to compare with
    }
    json.dumps(doc, allow_nan=False)


def test_run_benchmark_on_a_planar_problem() -> None:
    from drd_planner.data.planar_problem import make_planar_problem

    problem = make_planar_problem(num_worlds=100, max_paths=30, seed=1)
    res = run_benchmark(problem, policies=["bisect", "direct_bisect"], seed=0, max_worlds=4, progress=False)
    assert res.test_ids == problem.require_worlds().test_ids[:4].tolist()
    assert res.tree_info["nodes"] >= 1
    for stats in res.policies.values():
        assert len(stats.checks) == 4
        for c, bound in zip(stats.checks, res.lower_bound, strict=True):
            if not math.isnan(bound):
                assert c >= bound


# --------------------------------------------------------------------------------------------------
# bench --all, figures, Table-1 report
# --------------------------------------------------------------------------------------------------


@pytest.fixture
def two_dataset_root(tmp_path: Path) -> Path:
    """A root with symlinks to two small 2D datasets and one folder of another kind."""
    root = tmp_path / "root"
    root.mkdir()
    for name in ("dataset_2d_4", "dataset_2d_1"):
        (root / name).symlink_to(gccd_folder(name), target_is_directory=True)
    (root / "dataset_bern_test_1").mkdir()
    (root / "dataset_bern_test_1" / "test_set1.mat").write_bytes(b"")
    (root / "README.txt").write_text("not a folder")
    return root


def test_bench_all_runs_every_dataset(
    two_dataset_root: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out, md = tmp_path / "all.json", tmp_path / "all.md"
    argv = ["bench", "--all", str(two_dataset_root), "--max-worlds", "3", "--json", str(out)]
    assert main([*argv, "--markdown", str(md)]) == 0
    printed = capsys.readouterr().out
    assert "skipped dataset_bern_test_1: not an authors'-format graph dataset (missing graph.txt" in printed
    assert "total wall time" in printed
    doc = json.loads(out.read_text())
    assert {"software", "policies", "reference", "datasets", "skipped", "figures", "wall_seconds"} <= set(doc)
    assert doc["policies"] == list(DEFAULT_POLICIES)
    assert [d["dataset"] for d in doc["datasets"]] == ["dataset_2d_1", "dataset_2d_4"]  # sorted
    assert [s["folder"] for s in doc["skipped"]] == ["dataset_bern_test_1"]
    for ds in doc["datasets"]:
        assert DOC_KEYS <= set(ds)
        assert set(ds) - DOC_KEYS <= EXTRA_DOC_KEYS
        assert len(ds["test_ids"]) == 3
        assert set(ds["policies"]) == set(DEFAULT_POLICIES)
        for stats in ds["policies"].values():
            assert set(stats) == POLICY_KEYS | EXTRA_POLICY_KEYS
            assert len(stats["checks"]) == 3
            filtered = stats["relative"]["filtered"]
            assert set(filtered) == {"n", "p40", "p60", "median", "mean", "mean_ci"}
            assert filtered["n"] == ds["relative_protocol"]["num_kept"] <= 3
        assert ds["policies"]["direct_bisect"]["relative"]["unfiltered"]["p40"] == 0.0
        assert ds["settings"]["max_worlds"] == 3
    report = md.read_text()
    assert report in printed
    assert report.startswith("## Relative extra checks over `direct_bisect`")
    baselines = [p for p in DEFAULT_POLICIES if p != "direct_bisect"]
    assert "| dataset | n | " + " | ".join(baselines) + " |" in report
    for ds in doc["datasets"]:
        row = next(line for line in report.splitlines() if line.startswith(f"| {ds['dataset']} | "))
        rel = ds["policies"]["bisect"]["relative"]["filtered"]
        if rel["n"]:
            assert f"[{rel['p40']:.2f}, {rel['p60']:.2f}]" in row
    assert "## Mean selection time per check (ms)" in report
    assert "`dataset_bern_test_1`" in report


def test_bench_gccd_with_figures(d2d1: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    figs, out = tmp_path / "figs", tmp_path / "o.json"
    argv = [
        "bench",
        "--gccd",
        str(d2d1),
        "--max-worlds",
        "3",
        "--policies",
        "direct_bisect,bisect,direct_only",
    ]
    assert main([*argv, "--figures", str(figs), "--training-sizes", "50,100", "--json", str(out)]) == 0
    assert "wrote 8 figure files" in capsys.readouterr().out
    doc = json.loads(out.read_text())
    names = sorted(Path(p).name for p in doc["figures"])
    stems = ("checked_edges", "training_size", "checks_vs_cost")
    assert names == sorted(
        f"{stem}.{ext}"
        for stem in (*(f"{s}_dataset_2d_1" for s in stems), "normalised_costs")
        for ext in ("png", "svg")
    )
    for p in doc["figures"]:
        assert Path(p).stat().st_size > 1000
    assert doc["training_curve"]["sizes"] == [50, 100]


def test_bench_all_bad_folders_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "--all", str(tmp_path / "nope")]) == 2
    captured = capsys.readouterr()
    assert "dataset root not found" in _one_error_line(captured.err)
    assert captured.out == ""
    (tmp_path / "empty_dataset").mkdir()
    assert main(["bench", "--all", str(tmp_path)]) == 2
    assert "no dataset folder under" in _one_error_line(capsys.readouterr().err)


def test_bench_all_refuses_a_tree_file(two_dataset_root: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "--all", str(two_dataset_root), "--prior", "t.npz"]) == 2
    assert "--prior" in _one_error_line(capsys.readouterr().err)


@pytest.mark.parametrize(("flag", "value"), [("--max-worlds", "0"), ("--max-checks", "-1")])
def test_bench_rejects_non_positive_limits(
    d2d1: Path, flag: str, value: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["bench", "--gccd", str(d2d1), flag, value]) == 2
    assert flag in _one_error_line(capsys.readouterr().err)


def test_bench_needs_exactly_one_source(d2d1: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for argv in (["bench"], ["bench", "--gccd", str(d2d1), "--all", str(d2d1)]):
        with pytest.raises(SystemExit) as info:
            main(argv)
        assert info.value.code == 2
        assert "--gccd" in capsys.readouterr().err


def test_build_dataset_then_bench_and_plan_on_it(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data, tree, out = tmp_path / "pl.npz", tmp_path / "t.npz", tmp_path / "o.json"
    build = ["build-dataset", "--domain", "planar", "--world-model", "one_wall", "--worlds", "40"]
    assert main([*build, "--seed", "1", "--max-paths", "20", "--workers", "1", "--out", str(data)]) == 0
    assert main(["build-tree", "--dataset", str(data), "--out", str(tree)]) == 0
    argv = ["bench", "--dataset", str(data), "--prior", str(tree), "--policies", "direct_bisect,bisect"]
    assert main([*argv, "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["dataset"] == "pl"
    assert len(doc["test_ids"]) == 4
    assert doc["tree"]["nodes"] == load_tree_bundle(tree).tree.num_nodes
    assert doc["policies"]["bisect"]["relative"]["unfiltered"]["n"] == 4
    capsys.readouterr()
    assert main(["plan", "--dataset", str(data), "--tree", str(tree), "--world", str(doc["test_ids"][0])]) in (0, 1)
    assert "check   1:" in capsys.readouterr().out
    # A gccd tree does not fit a dataset of another domain.
    assert main(["bench", "--gccd", str(gccd_folder("dataset_2d_1")), "--prior", str(tree), "--max-worlds", "1"]) == 2
    _one_error_line(capsys.readouterr().err)


def test_build_tree_query_adds_trees_and_plan_uses_them(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from drd_planner.planner import load_prior

    d1 = gccd_folder("dataset_2d_1")
    prior = tmp_path / "p.npz"
    argv = ["build-tree", "--gccd", str(d1), "--out", str(prior), "--eta", "0.2", "--kappa", "none"]
    assert main([*argv, "--query", "3,40"]) == 0
    assert [(t.start, t.goal) for t in load_prior(prior).trees][1:] == [(3, 40)]
    states = load_prior(prior).graph.vertex_states
    assert states is not None
    text = f"{' '.join(str(v) for v in states[7])},{' '.join(str(v) for v in states[60])}"  # states snap
    assert main(["build-tree", "--prior", str(prior), "--query", text, "--out", str(prior)]) == 0
    assert [(t.start, t.goal) for t in load_prior(prior).trees][1:] == [(3, 40), (7, 60)]
    # Given eta and kappa leave the trees the prior's setting; 'auto' validates a tree's own on its query.
    assert [t.leaf is None for t in load_prior(prior).trees] == [True, True, False]
    assert "its own eta" in capsys.readouterr().out
    capsys.readouterr()
    assert main(["build-tree", "--prior", str(prior), "--query", "3,40", "--out", str(prior)]) == 2
    assert "already has a tree" in _one_error_line(capsys.readouterr().err)
    world = int(load_gccd_folder(d1).require_worlds().test_ids[0])
    assert main(["plan", "--tree", str(prior), "--gccd", str(d1), "--world", str(world), "--query", "7,60"]) in (0, 1)
    assert "query tree:7-60" in capsys.readouterr().out
    assert main(["plan", "--tree", str(prior), "--gccd", str(d1), "--world", str(world), "--query", "5,5000"]) == 1
    assert "refused" in capsys.readouterr().out
