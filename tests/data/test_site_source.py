"""``drd build-dataset --site-file``: a real site's worlds, end to end (site file -> dataset -> prior -> plan)."""

from __future__ import annotations

import shlex
import shutil
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO_ROOT
from test_dataset_builder import GridDomain

from drd_planner.cli.main import main
from drd_planner.data.dataset_file import load_dataset
from drd_planner.data.site_file import load_site
from drd_planner.data.site_source import open_worlds, resolve, spec_defaults
from drd_planner.data.world_sources import FileRecord, SiteFile
from drd_planner.domains.base import domain_from_spec
from drd_planner.exceptions import DatasetError

pytest.importorskip("rasterio")
pytest.importorskip("osmium")

SITE = REPO_ROOT / "sites" / "front_range"

#: The bundled site's lattice made small: two altitudes, headings within 90 degrees (674 edges).
SMALL = (
    "lattice:\n  file: spec.json\n"
    "  lattice: {z_levels: [60, 120], start_level: 0, goal_level: 0, max_heading_deg: 90}\n"
)


@pytest.fixture
def small_site(tmp_path: Path) -> Path:
    """The bundled site with a small lattice, in a temporary folder."""
    folder = tmp_path / "site"
    shutil.copytree(SITE, folder)
    shutil.copy(REPO_ROOT / "trees" / "heli_lines_spec.json", folder / "spec.json")
    text = (folder / "site.yaml").read_text()
    text = text.replace("lattice: ../../trees/heli_lines_spec.json", SMALL.rstrip("\n"))
    (folder / "site.yaml").write_text(text)
    return folder / "site.yaml"


def test_the_spec_defaults_are_the_sites_and_other_domains_are_refused(small_site: Path) -> None:
    request = SiteFile(str(small_site))
    spec = spec_defaults(request, "helicopter")
    assert spec == load_site(small_site).domain_spec
    assert spec_defaults(request, "grid_test") == {}
    with pytest.raises(DatasetError, match="--site-file describes a helicopter site: use --domain helicopter"):
        resolve(request, GridDomain(), {}, 3)


def test_every_site_file_is_hashed_and_a_changed_dem_is_refused_by_the_worker(small_site: Path) -> None:
    request = SiteFile(str(small_site))
    domain = domain_from_spec("helicopter", spec_defaults(request, "helicopter"))
    resolved = resolve(request, domain, spec_defaults(request, "helicopter"), None)
    assert resolved.num_worlds == 200
    assert resolved.world_model == "corridors"
    assert resolved.seeded
    names = sorted(Path(f["path"]).name for f in resolved.provenance["files"])
    assert names == ["dem.tif", "power.osm", "site.yaml", "spec.json", "zones.geojson"]
    assert resolved.provenance["lines"] == ["West Feeder", "East Trunk", "Valley Tap", "Ridge Tap"]
    worlds = open_worlds(resolved.worker_data)
    assert [r.path for r in worlds.records] == [str(small_site.parent / "dem.tif")]
    (small_site.parent / "dem.tif").write_bytes((small_site.parent / "dem.tif").read_bytes() + b"\0")
    with pytest.raises(DatasetError, match=r"dem\.tif changed since the build was planned"):
        open_worlds(resolved.worker_data)


def test_a_bad_site_file_is_one_error_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "site.yaml"
    path.write_text("format: drd-site/1\nnme: x\n")
    assert main(["build-dataset", "--site-file", str(path), "--out", str(tmp_path / "ds.npz")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("drd: error: site file ")
    assert "unknown key(s) ['nme']" in err
    assert "\n" not in err


@pytest.mark.slow
def test_site_file_to_dataset_to_prior_to_a_plan(
    small_site: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out, prior = tmp_path / "ds.npz", tmp_path / "prior.npz"
    argv = ["build-dataset", "--site-file", str(small_site), "--worlds", "10", "--test-fraction", "0.3"]
    assert main([*argv, "--workers", "1", "--no-trajectories", "--out", str(out)]) == 0
    assert "worlds: site 'front_range' (5 files): corridors model on the DEM" in capsys.readouterr().out
    ds = load_dataset(out)
    assert ds.world_model == "corridors"
    assert ds.num_worlds == 10
    assert ds.domain_spec["models"]["corridors"]["path"] == str(small_site.parent / "dem.tif")
    source = ds.provenance["world_source"]
    assert {Path(f["path"]).name: f["sha256"] for f in source["files"]}["site.yaml"] == FileRecord.of(small_site).sha256
    command = ds.provenance["command"]
    assert "--site-file" in command
    assert "--domain helicopter" in command
    assert "--seed 1" in command
    # the worlds are the corridors model's seeded draws over the site
    domain = domain_from_spec("helicopter", ds.domain_spec)
    edges = np.arange(domain.graph.num_edges)
    first = domain.checker(domain.make_world("corridors", int(ds.world_seeds[0]))).check_many(edges)
    assert np.array_equal(ds.X[0], first)
    again = tmp_path / "again.npz"
    assert main([*shlex.split(command)[1:], "--workers", "1", "--out", str(again)]) == 0
    assert again.read_bytes() == out.read_bytes()
    assert main(["build-tree", "--dataset", str(out), "--out", str(prior)]) == 0
    capsys.readouterr()
    world = int(np.flatnonzero(np.isin(np.arange(ds.num_worlds), ds.test_ids))[0])
    assert main(["plan", "--prior", str(prior), "--dataset", str(out), "--world", str(world)]) == 0
    assert "-> found: path of" in capsys.readouterr().out
