"""Site files: the bundled site read into corridors parameters, and every kind of bad site file refused."""

from __future__ import annotations

import dataclasses
import shutil
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO_ROOT, SHARED_DATA

from drd_planner.data.site_file import SITE_FORMAT, load_site
from drd_planner.domains.helicopter import HelicopterDomain
from drd_planner.domains.helicopter_corridors_model import CorridorsModel
from drd_planner.domains.helicopter_corridors_params import CorridorsParams
from drd_planner.domains.helicopter_spec import HelicopterParams
from drd_planner.exceptions import SiteFileError

pytest.importorskip("rasterio")
pytest.importorskip("osmium")

SITE = REPO_ROOT / "sites" / "front_range"


@pytest.fixture
def site_copy(tmp_path: Path) -> Path:
    """The bundled site's files in a temporary folder (the lattice spec beside them)."""
    folder = tmp_path / "site"
    shutil.copytree(SITE, folder)
    shutil.copy(REPO_ROOT / "trees" / "heli_lines_spec.json", folder / "spec.json")
    text = (folder / "site.yaml").read_text().replace("../../trees/heli_lines_spec.json", "spec.json")
    (folder / "site.yaml").write_text(text)
    return folder / "site.yaml"


def _edit(path: Path, old: str, new: str) -> Path:
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new))
    return path


def test_the_bundled_site_gives_lines_zones_and_a_domain_spec() -> None:
    site = load_site(SITE / "site.yaml")
    assert site.path == str((SITE / "site.yaml").resolve())
    assert site.name == "front_range"
    lat, lon, datum = site.origin
    assert (lat, lon, datum) == (40.1825, -105.4617, "DEM")
    p = site.corridors
    assert isinstance(p, CorridorsParams)
    assert p.path == str((SITE / "dem.tif").resolve())
    assert p.grid_units == "degrees"
    assert p.datum is None
    assert p.site_origin == pytest.approx((-105.4617, 40.1825))
    assert p.site_heading_deg == pytest.approx(90.0)
    assert (p.shift_sigma, p.bias_sigma) == (10.0, 15.0)
    assert (p.unmapped_lines, p.unmapped_towers) == ((0, 1), (0, 2))
    assert (p.unmapped_line.tower_height, p.unmapped_line.sag, p.unmapped_line.probability) == ((40, 60), (4, 15), 1.0)
    assert [line.name for line in p.lines] == ["West Feeder", "East Trunk", "Valley Tap", "Ridge Tap"]
    assert {line.probability for line in p.lines} == {0.7}
    feeder = np.asarray(p.lines[0].route)  # drawn along x = 450..600 m, y = -1400..1400 m, clipped at 1350 m
    assert 430 < feeder[:, 0].min() < feeder[:, 0].max() < 620
    assert np.abs(feeder[:, 1]).max() == pytest.approx(1350)
    assert [z.name for z in p.zones] == ["mast_0", "Airfield shelf", "Exercise_1", "Exercise_2", "Quarry", "Range west"]
    shelf = p.zones[1]
    assert shelf.center == pytest.approx((1550.0, -1000.0), abs=1.0)
    assert shelf.z_range == (90.0, 3000.0)
    assert sorted(shelf.size) == pytest.approx([800.0, 1500.0], abs=1.0)
    assert p.zones[2].group == p.zones[3].group == "Exercise"
    spec = HelicopterParams.from_spec(site.domain_spec)
    assert spec.lattice.x_range == (0.0, 2500.0)
    assert spec.terrain_cell == 30.0
    assert spec.model("corridors") == p
    assert site.world_model == "corridors"
    assert (site.worlds, site.seed) == (200, 1)
    assert len(site.files) == 5
    assert all(Path(f).is_file() for f in site.files)
    with pytest.raises(dataclasses.FrozenInstanceError):
        site.name = "other"  # type: ignore[misc]


def test_the_domain_draws_worlds_over_the_real_terrain() -> None:
    site = load_site(SITE / "site.yaml")
    domain = HelicopterDomain.from_spec(site.domain_spec)
    world = domain.make_world("corridors", 3)
    info = world.info["model"] if "model" in world.info else world.info
    assert info["datum"] == pytest.approx(CorridorsModel().site(site.corridors).heights(np.zeros(1), np.zeros(1))[0])
    assert 2000.0 < info["datum"] < 3000.0  # the Front Range near Boulder, metres above EGM96


@pytest.mark.skipif(not (SHARED_DATA / "terrain" / "srtm_front_range_144.asc").is_file(), reason="no shared SRTM grid")
def test_the_geotiff_crop_gives_the_heights_of_the_shared_ascii_grid() -> None:
    site = load_site(SITE / "site.yaml")
    ascii_params = dataclasses.replace(site.corridors, path=str(SHARED_DATA / "terrain" / "srtm_front_range_144.asc"))
    x, y = np.meshgrid(np.linspace(-100, 2600, 7), np.linspace(-1300, 1300, 7))
    tif = CorridorsModel().site(site.corridors).heights(x, y)
    asc = CorridorsModel().site(ascii_params).heights(x, y)
    assert np.isfinite(tif).all()
    np.testing.assert_allclose(tif, asc, atol=0.01)


def test_relative_paths_are_read_from_the_site_files_folder(site_copy: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir("/")
    site = load_site(site_copy)
    assert site.corridors.path == str(site_copy.parent / "dem.tif")


def test_datums_set_the_height_of_z_zero(site_copy: Path) -> None:
    _edit(site_copy, "datum: DEM ", "datum: EGM96\n  height_m: 2400 ")
    assert load_site(site_copy).corridors.datum == 2400.0
    _edit(site_copy, "\n  datum: EGM96", "\n  datum: WGS84 ellipsoid")
    with pytest.raises(SiteFileError, match=r"give origin\.geoid_separation_m"):
        load_site(site_copy)
    _edit(site_copy, "height_m: 2400", "height_m: 2400\n  geoid_separation_m: -16.9")
    assert load_site(site_copy).corridors.datum == pytest.approx(2416.9)


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("format: drd-site/1", "format: drd-site/9", f"format must be '{SITE_FORMAT}'"),
        ("name: front_range", "nmae: front_range", r"unknown key\(s\) \['nmae'\]; valid keys: format, name, dem"),
        ("  vertical_datum: EGM96", "  vertical_datum: NAVD88", "dem.vertical_datum must be one of 'EGM96'"),
        ("path: dem.tif", "path: nothere.tif", r"dem.path: file .*nothere.tif not found"),
        ("latitude: 40.1825", "latitude: 47.0", "does not cover the lattice around the origin"),
        ("heading_deg: 0 ", "heading_deg: 0\n  speed: 3 ", r"origin: unknown key\(s\) \['speed'\]"),
        ("line_probability: 0.7", "line_probability: 7", "uncertainty.line_probability must be a probability"),
        ("  seed: 1", "  seed: -1", "dataset.seed must be an integer >= 0"),
        ("unmapped_lines: [0, 1]", "unmapped_lines: [2, 1]", r"uncertainty.unmapped_lines must be \[lo, hi\]"),
        ("unmapped_towers: [0, 2]", "unmapped_towers: [0, 1.5]", "uncertainty.unmapped_towers must be whole"),
        ("lattice: spec.json", "lattice: {file: spec.json, vehicle_radius: -1}", "lattice: helicopter spec"),
        ("lattice: spec.json", "lattice: {file: spec.json, wings: 2}", r"unknown key\(s\) \['wings'\]"),
        ("power_lines: power.osm", "power_lines: zones.geojson", "must end in one of .osm"),
        ("zones: zones.geojson", "zones: power.osm", "is not valid JSON"),
        ("dem:\n", "dem:\n  crs: EPSG:32613\n", "does not match the CRS of GeoTIFF"),
    ],
)
def test_bad_site_files_get_one_error_naming_the_key(site_copy: Path, old: str, new: str, message: str) -> None:
    _edit(site_copy, old, new)
    with pytest.raises(SiteFileError, match=message):
        load_site(site_copy)


def test_missing_sections_and_an_alias(tmp_path: Path) -> None:
    path = tmp_path / "site.yaml"
    path.write_text(f"format: {SITE_FORMAT}\n")
    with pytest.raises(SiteFileError, match="dem is required"):
        load_site(path)
    path.write_text(f"format: {SITE_FORMAT}\nname: &n x\nother: *n\n")
    with pytest.raises(SiteFileError, match="anchors and aliases"):
        load_site(path)
