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


def test_a_site_file_gives_the_site_of_its_corridors_parameters_on_its_lattice(monkeypatch: pytest.MonkeyPatch) -> None:
    """The hook against the announced reader: ``load_site(path)`` with ``.corridors`` and ``.domain_spec``."""
    import sys
    import types

    from drd_planner.domains.helicopter_corridors_params import CorridorsParams
    from drd_planner.planner import load_prior
    from drd_planner.planning import site_source

    spec = load_prior(ROOT / "trees" / "heli_lines.npz").domain_spec
    corridors = CorridorsParams(**{**spec["models"]["corridors"], "lines": (), "zones": (), "datum": 2400.0})
    read: list[str] = []

    def load_site(path: str) -> types.SimpleNamespace:
        read.append(path)
        return types.SimpleNamespace(corridors=corridors, domain_spec=spec, origin=(0.0, 0.0))

    fake = types.ModuleType(site_source.SITE_FILE_MODULE)
    fake.load_site = load_site  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, site_source.SITE_FILE_MODULE, fake)
    monkeypatch.setattr(site_source, "SITE_FILES", True)
    lines: list[str] = []
    site = site_of_site_file("/data/front_range.yaml", log=lines.append)
    assert read == ["/data/front_range.yaml"]
    assert lines == ["loading site file /data/front_range.yaml"]
    assert site.name == "front_range"
    assert site.params is corridors
    assert site.datum == 2400.0
    assert site.frame.x_range == (0.0, 2500.0)  # the lattice of the file's domain spec
