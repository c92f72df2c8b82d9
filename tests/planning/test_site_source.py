"""Where a map server's site comes from: a site prior (shipped name or path), never a prior of no site."""

from __future__ import annotations

from pathlib import Path

import pytest

from drd_planner.exceptions import DrdError
from drd_planner.planning.site_source import SITE_FILES, site_of_prior_file, site_of_site_file

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


@pytest.mark.skipif(SITE_FILES, reason="this install reads site files")
def test_without_the_site_file_reader_a_site_file_is_refused_naming_the_missing_module() -> None:
    with pytest.raises(DrdError, match=r"reads no site files \(drd_planner.data.site_file is missing\)"):
        site_of_site_file("site.yaml")
