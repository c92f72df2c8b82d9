"""Where a map server's site comes from: a site prior (shipped name or path), never a prior of no site."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from drd_planner.data.site_file import load_site
from drd_planner.exceptions import DrdError
from drd_planner.planning.served_site import site_of_prior_file, site_of_site_file

ROOT = Path(__file__).resolve().parents[2]


def test_a_site_prior_gives_its_site_by_name_or_path_with_progress_lines() -> None:
    lines: list[str] = []
    site = site_of_prior_file("heli_lines", log=lines.append)
    assert site.name == "heli_lines"
    assert site.frame.x_range == (0.0, 2500.0)
    assert lines == [f"loading prior {ROOT / 'trees' / 'heli_lines.npz'}"]
    again = site_of_prior_file(str(ROOT / "trees" / "heli_lines.npz"))
    assert again.datum == site.datum


def test_a_prior_of_no_site_or_no_prior_is_one_error_naming_it() -> None:
    with pytest.raises(DrdError, match=r"heli_wires.npz is not a prior of a real site \(domain 'helicopter'"):
        site_of_prior_file("heli_wires")
    with pytest.raises(DrdError, match=r"arm_table_clutter.npz is not a prior of a real site \(domain 'arm'"):
        site_of_prior_file("arm_table_clutter")
    with pytest.raises(DrdError, match=r"neither a file nor missing\.npz"):
        site_of_prior_file("missing")


def test_a_site_file_gives_the_site_of_its_corridors_parameters_on_its_lattice() -> None:
    path = ROOT / "sites" / "front_range" / "site.yaml"
    lines: list[str] = []
    site = site_of_site_file(str(path), log=lines.append)
    assert lines == [f"loading site file {path}"]
    assert site.name == "front_range"  # the name the file gives
    read = load_site(path)
    assert site.params == read.corridors
    assert len(site.params.lines) > 0
    assert len(site.params.zones) > 0
    assert site.frame.x_range == (0.0, 2500.0)  # the lattice of the file's spec (trees/heli_lines_spec.json)
    heights = site.grid.heights(np.array([0.0, 2500.0]), np.array([0.0, -1000.0]))
    assert np.all(np.isfinite(heights))


def test_a_bad_site_file_is_one_error_naming_it(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("format: drd-site/9\n")
    with pytest.raises(DrdError, match=r"bad\.yaml"):
        site_of_site_file(str(bad))
