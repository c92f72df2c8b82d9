"""Optional extras stay optional: every command runs without matplotlib and OMPL, or names the extra."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from conftest import gccd_folder

from drd_planner.bench.extras import EXTRAS, MissingExtraError, install_hint, require_extra

#: Runs a console entry point (module:function, then its argv) with every extra's module unimportable.
WITHOUT_EXTRAS = """
import importlib, sys
for name in {modules!r}:
    sys.modules[name] = None  # what "not installed" looks like to import
module, function = sys.argv[1].split(":")
sys.exit(getattr(importlib.import_module(module), function)(sys.argv[2:]))
"""


def _run_bare(entry: str, *args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    code = WITHOUT_EXTRAS.format(modules=sorted(EXTRAS.values()))
    return subprocess.run(
        [sys.executable, "-c", code, entry, *args],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=cwd,
        check=False,
    )


def test_require_extra_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(MissingExtraError, match=r"drd bench --figures needs the 'plots' extra") as info:
        require_extra("plots", "drd bench --figures")
    assert install_hint("plots") in str(info.value)
    assert install_hint("plots") == "pip install -e 'ros2_ws/src/drd_planner[plots]'"


def test_bench_runs_without_extras(tmp_path: Path) -> None:
    folder = gccd_folder("dataset_2d_1")
    out = tmp_path / "bench.json"
    args = ["--gccd", str(folder), "--max-worlds", "2", "--eta", "0.2", "--kappa", "none"]
    policies = ["--policies", "bisect,direct_bisect,ompl_lazyprm", "--json", str(out)]
    proc = _run_bare("drd_planner.cli.main:main", "bench", *args, *policies, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "| dataset_2d_1 |" in proc.stdout
    assert out.is_file()
    assert f"ompl_lazyprm skipped: OMPL not installed (the 'peer' extra): {install_hint('peer')}" in proc.stderr


def test_bench_figures_without_matplotlib_names_the_extra(tmp_path: Path) -> None:
    folder = gccd_folder("dataset_2d_1")
    args = ["--gccd", str(folder), "--max-worlds", "2", "--figures", str(tmp_path / "figs")]
    proc = _run_bare("drd_planner.cli.main:main", "bench", *args, cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stdout == ""
    assert proc.stderr.strip() == (
        f"drd: error: drd bench --figures needs the 'plots' extra (matplotlib): {install_hint('plots')}"
    )
    assert not (tmp_path / "figs").exists()


def test_planner_demo_without_pictures_runs_without_extras(tmp_path: Path) -> None:
    proc = _run_bare("drd_planner.cli.planner_demo:main", "--no-pictures", "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert (tmp_path / "out" / "outputs.mcap").is_file()
    assert not list((tmp_path / "out").glob("*.png"))
