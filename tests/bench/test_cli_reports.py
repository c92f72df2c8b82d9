"""What ``drd`` tells a new user: progress off a terminal, short summaries, quick runs, refusals, notes."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from conftest import gccd_folder

from drd_planner import progress
from drd_planner.cli.main import main
from drd_planner.core.switch_threshold import DEFAULT_ETA_CANDIDATES
from drd_planner.data.gccd import load_gccd_folder

#: Longest line a summary may print (the old one-line eta report had 670-900 characters).
MAX_LINE = 110


@pytest.fixture(scope="module")
def d2d1() -> Path:
    return gccd_folder("dataset_2d_1")


@pytest.fixture
def every_update_reported(monkeypatch: pytest.MonkeyPatch) -> None:
    """Plain progress lines for every unit of work (capsys's stderr is not a terminal)."""
    monkeypatch.setattr(progress, "PLAIN_INTERVAL_S", 0.0)


@pytest.mark.usefixtures("every_update_reported")
def test_build_tree_reports_progress_and_a_short_summary(
    d2d1: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "p.npz"
    assert main(["build-tree", "--gccd", str(d2d1), "--out", str(out), "--kappa", "none"]) == 0
    captured = capsys.readouterr()
    lines = captured.out.splitlines()
    assert max(len(line) for line in lines if not line.startswith("wrote ")) <= MAX_LINE, captured.out
    validated = re.match(r"eta [\d.]+, fixed leaf: validated in ([\d.]+) s on 64 episodes", lines[0])
    assert validated, lines[0]
    assert "random queries" in lines[0]
    # --region-rule auto (the default): both rules validated, each one's best mean reported
    assert re.match(
        r"  region rule (probability|per_check) \(best mean checks: probability [\d.]+, per_check", lines[1]
    )
    assert lines[2].split()[:3] == ["mean", "checks", "fixed"]
    assert sum(line.startswith("  eta ") for line in lines) >= len(DEFAULT_ETA_CANDIDATES)  # a row per eta
    assert any(line.startswith("tree dataset_2d_1 ") and "built in" in line for line in lines)
    done = re.fullmatch(r"done in ([\d.]+) s .*", lines[-1])
    # validation included
    assert done
    assert float(done.group(1)) >= float(validated.group(1)) - 0.05
    err = captured.err.splitlines()
    total = len(DEFAULT_ETA_CANDIDATES) * 2 * 64  # eta candidates x 2 rules x 64 episodes
    assert err[0] == f"validating eta x kappa x region rule: {total} episodes"
    assert any(re.match(rf"validating eta x kappa x region rule: \d+/{total} episodes \(\d+%\)", line) for line in err)


@pytest.mark.usefixtures("every_update_reported")
def test_bench_max_worlds_also_limits_the_validation(
    d2d1: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "new" / "folder" / "b.json"  # folders are made
    argv = ["bench", "--gccd", str(d2d1), "--max-worlds", "3", "--policies", "direct_bisect,bisect"]
    assert main([*argv, "--kappa", "none", "--json", str(out)]) == 0
    captured = capsys.readouterr()
    selection = json.loads(out.read_text())["settings"]["eta_selection"]
    assert selection["num_validation_worlds"] == 3
    lines = captured.out.splitlines()
    summary = next(line for line in lines if line.startswith("dataset_2d_1: eta "))
    assert "validated in" in summary
    assert "on 3 held-out training worlds" in summary
    assert len(summary) <= MAX_LINE
    total = re.fullmatch(r"total wall time ([\d.]+) s \(eta and kappa validation ([\d.]+) s of it\)", lines[-1])
    assert total
    assert float(total.group(1)) >= float(total.group(2))
    assert float(total.group(2)) == pytest.approx(selection["seconds"], abs=0.06)
    err = captured.err
    etas = len(DEFAULT_ETA_CANDIDATES)
    assert f"validating eta x kappa: {etas * 3} episodes" in err  # eta candidates x 1 kappa x 3 worlds
    assert re.search(r"^dataset_2d_1 episodes: 1/6 episodes \(17%\), .* \[direct_bisect\]$", err, flags=re.M)
    assert re.search(r"^dataset_2d_1 episodes: 4/6 episodes \(67%\), .* \[bisect\]$", err, flags=re.M)
    assert "dataset_2d_1 episodes: 6/6 episodes done in" in err


def _one_error_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("drd: error:"), err
    return lines[0]


def test_a_dataset_without_test_worlds_is_refused_by_bench(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = tmp_path / "train_only.npz"
    build = ["build-dataset", "--domain", "planar", "--world-model", "one_wall", "--worlds", "40"]
    argv = [*build, "--seed", "1", "--max-paths", "20", "--workers", "1", "--test-fraction", "0"]
    assert main([*argv, "--out", str(data)]) == 0
    assert "note: no test worlds" in capsys.readouterr().out
    for extra in ([], ["--queries", "3"]):
        assert main(["bench", "--dataset", str(data), "--policies", "direct_bisect,bisect", *extra]) == 2
        captured = capsys.readouterr()
        assert "no test worlds" in _one_error_line(captured.err), extra
        assert "nan" not in captured.out
        assert "validat" not in captured.err
    # Training needs no test worlds: the prior is still written.
    assert main(["build-tree", "--dataset", str(data), "--out", str(tmp_path / "p.npz"), "--eta", "0.2"]) == 0


def test_plan_on_a_training_world_says_so(d2d1: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    prior = tmp_path / "p.npz"
    assert main(["build-tree", "--gccd", str(d2d1), "--out", str(prior), "--eta", "0.2", "--kappa", "none"]) == 0
    worlds = load_gccd_folder(d2d1).require_worlds()
    for world, training in ((int(worlds.train_ids[0]), True), (int(worlds.test_ids[0]), False)):
        capsys.readouterr()
        assert main(["plan", "--tree", str(prior), "--gccd", str(d2d1), "--world", str(world)]) in (0, 1)
        out = capsys.readouterr().out
        assert (f"note: world {world} is a training world" in out) == training, out
