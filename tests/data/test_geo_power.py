"""Power lines and towers from OSM XML and PBF: what is read, and the files that are refused."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import REPO_ROOT

from drd_planner.data import geo_power
from drd_planner.data.geo_power import read_power
from drd_planner.exceptions import SiteFileError

osmium = pytest.importorskip("osmium")

OSM = REPO_ROOT / "sites" / "front_range" / "power.osm"


def _osm(path: Path, body: str) -> Path:
    path.write_text(f"<?xml version='1.0' encoding='UTF-8'?>\n<osm version=\"0.6\">\n{body}\n</osm>\n")
    return path


NODES = (
    '<node id="1" version="1" lat="40.18" lon="-105.46"><tag k="power" v="tower"/></node>'
    '<node id="2" version="1" lat="40.19" lon="-105.46"/>'
    '<node id="3" version="1" lat="40.20" lon="-105.45"><tag k="power" v="pole"/></node>'
)


def test_the_bundled_extract_has_its_lines_towers_and_mast() -> None:
    power = read_power(OSM)
    assert [w.name for w in power.lines] == ["West Feeder", "East Trunk", "Valley Tap", "Ridge Tap"]
    assert [w.power for w in power.lines] == ["line", "line", "minor_line", "minor_line"]
    assert all(power.lines[0].towers)
    assert not all(power.lines[2].towers)
    on_lines = sum(sum(w.towers) for w in power.lines)
    assert len(power.towers) == on_lines + 1  # the mast stands on no line
    lon, lat = zip(*power.lines[0].points, strict=True)
    assert -105.5 < min(lon) < max(lon) < -105.4
    assert 40.17 < min(lat) < max(lat) < 40.21


def test_ways_keep_their_node_order_and_tower_flags(tmp_path: Path) -> None:
    way = '<way id="7" version="1"><nd ref="3"/><nd ref="2"/><nd ref="1"/><tag k="power" v="minor_line"/></way>'
    power = read_power(_osm(tmp_path / "a.osm", NODES + way))
    (line,) = power.lines
    assert line.name == "way_7"
    assert line.points[0] == (-105.45, 40.2)
    assert line.towers == (True, False, True)


def test_pbf_is_read_too(tmp_path: Path) -> None:
    way = '<way id="7" version="1"><nd ref="1"/><nd ref="2"/><tag k="power" v="line"/><tag k="ref" v="L7"/></way>'
    src = _osm(tmp_path / "a.osm", NODES + way)
    out = tmp_path / "a.pbf"
    writer = osmium.SimpleWriter(str(out))
    for obj in osmium.FileProcessor(str(src)):
        writer.add(obj)
    writer.close()
    assert [w.name for w in read_power(out).lines] == ["L7"]


def test_a_file_without_power_ways_is_refused(tmp_path: Path) -> None:
    way = '<way id="7" version="1"><nd ref="1"/><nd ref="2"/><tag k="highway" v="track"/></way>'
    with pytest.raises(SiteFileError, match="has no power lines: no way tagged power=line or power=minor_line"):
        read_power(_osm(tmp_path / "a.osm", NODES + way))


def test_incomplete_ways_malformed_xml_endings_and_size(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    way = '<way id="7" version="1"><nd ref="1"/><nd ref="9"/><tag k="power" v="line"/></way>'
    with pytest.raises(SiteFileError, match=r"refers to nodes not in the file \(\[9\]\)"):
        read_power(_osm(tmp_path / "a.osm", NODES + way))
    bad = tmp_path / "b.osm"
    bad.write_text("<osm><node id=")
    with pytest.raises(SiteFileError, match="cannot be read as OSM"):
        read_power(bad)
    with pytest.raises(SiteFileError, match=r"must end in one of \.osm, \.xml, \.pbf"):
        read_power(tmp_path / "a.geojson")
    monkeypatch.setattr(geo_power, "MAX_OSM_BYTES", 100)
    with pytest.raises(SiteFileError, match="at most 100 are read"):
        read_power(tmp_path / "a.osm")
