"""``planner_demo --prior P --site-file S``: a prior built from the bundled site, served live by the map server."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS or the PyPI wheels) not installed")
pytest.importorskip("rasterio")
pytest.importorskip("osmium")

from conftest import REPO_ROOT
from harness import use_domain

from drd_msgs_py.bags import open_bag
from drd_planner.cli.main import main as drd
from drd_planner.cli.planner_demo import main
from drd_planner.data.problem_source import ProblemSource
from drd_planner.planner.prior_build import BuildTreeOptions, write_prior

pytestmark = pytest.mark.slow  # builds a small dataset and prior, then two nodes; about 30 s

use_domain(50)

#: The bundled site's lattice made small: two altitudes above the wires' towers, every heading (5399 edges).
SMALL = (
    "lattice:\n  file: spec.json\n"
    "  lattice: {z_levels: [100, 140], start_level: 0, goal_level: 0, max_heading_deg: 180}"
)


def _small_site(folder: Path) -> Path:
    """The bundled site with a small lattice, copied into ``folder``."""
    shutil.copytree(REPO_ROOT / "sites" / "front_range", folder)
    shutil.copy(REPO_ROOT / "trees" / "heli_lines_spec.json", folder / "spec.json")
    text = (folder / "site.yaml").read_text()
    assert "lattice: ../../trees/heli_lines_spec.json" in text
    (folder / "site.yaml").write_text(text.replace("lattice: ../../trees/heli_lines_spec.json", SMALL))
    return folder / "site.yaml"


def _plans(out: str) -> list[tuple[set[int], list[int]]]:
    """Per printed plan: the edges its check log found free (checked now or cached), and its path's edges."""
    plans: list[tuple[set[int], list[int]]] = []
    for block in re.split(r"\n(?=plan \d+: )", out)[1:]:
        free = {int(m) for m in re.findall(r"check +\d+: edge +(\d+) \S+ +free ", block)}
        path = re.search(r"path: edges \[([\d, ]*)\]", block)
        plans.append((free, [int(e) for e in path.group(1).split(",")] if path else []))
    return plans


def test_site_mode_plans_on_the_map_servers_maps_and_draws(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("matplotlib", reason="the plots extra is not installed")
    site = _small_site(tmp_path / "site")
    dataset, prior = tmp_path / "ds.npz", tmp_path / "prior.npz"
    argv = ["build-dataset", "--site-file", str(site), "--worlds", "8", "--test-fraction", "0.3", "--workers", "1"]
    assert drd([*argv, "--no-trajectories", "--out", str(dataset)]) == 0
    assert write_prior(BuildTreeOptions(out=str(prior), source=ProblemSource(dataset=str(dataset)))) == 0
    capsys.readouterr()
    out_dir = tmp_path / "out"
    status = main(["--prior", str(prior), "--site-file", str(site), "--out", str(out_dir), "--rate", "4"])
    out = capsys.readouterr().out
    assert status in (0, 1), out  # 1: a goal the site's known lines and zones leave unreachable
    assert "map server: site front_range" in out
    plans = _plans(out)
    assert len(plans) == 3  # the stored query, then two far vertices
    found = [(free, path) for free, path in plans if path]
    assert all(path for _, path in plans[1:]), out  # the far goals are reachable on the served maps
    for free, path in found:  # a published path: every edge was checked free on the served maps
        assert set(path) <= free
    for k in range(len(plans)):
        assert (out_dir / f"plan_{k}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    recorded = open_bag(out_dir / "outputs.mcap")
    assert {"/plan", "/edge_checks", "/checked_edges"} <= set(recorded.topics)
    assert recorded.topics["/edge_checks"].count == 3


def test_site_mode_needs_a_prior_and_no_bag(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    site = str(REPO_ROOT / "sites" / "front_range" / "site.yaml")
    for argv in (["--site-file", site], ["--site-file", site, "--prior", "p.npz", "--bag", "heli_lines"]):
        with pytest.raises(SystemExit) as exit_:
            main(argv)
        assert exit_.value.code == 2
        assert "--site-file needs --prior" in capsys.readouterr().err
