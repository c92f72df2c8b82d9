"""Mapped lines and zones moved into the lattice frame: clipping, spans, rectangles and keep-clear refusals."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.data.geo_frame import SiteFrame
from drd_planner.data.geo_power import OsmPower, PowerWay
from drd_planner.data.geo_zones import GeoZone, GeoZones
from drd_planner.data.site_convert import MAST_RADIUS, LineDefaults, known_lines, known_zones, mast_zones
from drd_planner.exceptions import SiteFileError

pytest.importorskip("shapely")
pytest.importorskip("pyproj")

FRAME = SiteFrame(40.1825, -105.4617, 0.0)
REGION = ((-100.0, 2600.0), (-1350.0, 1350.0))
KEEP = ([(0.0, 0.0), (2500.0, -1000.0)], 67.0)


def _lonlat(xy: list[tuple[float, float]]) -> tuple[tuple[float, float], ...]:
    lon, lat = FRAME.from_lattice([p[0] for p in xy], [p[1] for p in xy])
    return tuple(zip(lon.tolist(), lat.tolist(), strict=True))


def _power(*ways: PowerWay, towers: tuple[tuple[float, float], ...] = ()) -> OsmPower:
    return OsmPower("x.osm", ways, towers)


def test_a_line_is_clipped_to_the_region_in_pieces_with_the_default_span() -> None:
    # leaves the region east of y = -1350 between its 2nd and 3rd points and comes back
    route = [(500.0, -1000.0), (800.0, -1300.0), (1000.0, -2000.0), (1200.0, -1300.0), (1400.0, -1000.0)]
    way = PowerWay(5, "L", "line", _lonlat(route), (False,) * 5)
    lines = known_lines(_power(way), FRAME, REGION, LineDefaults(), KEEP)
    assert [line["name"] for line in lines] == ["L", "L_2"]
    for line in lines:
        xy = np.asarray(line["route"])
        assert xy[:, 1].min() >= -1350.0 - 1e-6
        assert line["span"] == [250.0, 400.0]
        assert line["probability"] == 0.8
    np.testing.assert_allclose(lines[0]["route"][0], route[0], atol=0.01)


def test_a_line_on_mapped_towers_gets_its_longest_leg_as_span_and_names_stay_unique() -> None:
    route = [(400.0, -500.0), (600.0, -500.0), (900.0, -500.0)]
    a = PowerWay(1, "L", "line", _lonlat(route), (True, True, True))
    b = PowerWay(2, "L", "line", _lonlat([(400.0, 500.0), (900.0, 500.0)]), (True, False))
    lines = known_lines(_power(a, b), FRAME, REGION, LineDefaults(), KEEP)
    assert [line["name"] for line in lines] == ["L", "L_2"]
    assert lines[0]["span"] == pytest.approx([301.0, 301.0], abs=0.05)
    assert lines[1]["span"] == [250.0, 400.0]


def test_a_line_or_zone_over_the_start_is_refused_by_name() -> None:
    way = PowerWay(3, "Over start", "line", _lonlat([(30.0, -500.0), (30.0, 500.0)]), (False, False))
    with pytest.raises(SiteFileError, match=r"power line 'Over start' \(OSM way 3\) comes within 30 m"):
        known_lines(_power(way), FRAME, REGION, LineDefaults(), KEEP)
    ring = _lonlat([(2450.0, -1050.0), (2600.0, -1050.0), (2600.0, -900.0), (2450.0, -900.0)])
    zones = GeoZones("z", "OGC:CRS84", (GeoZone("Goal pad", (ring,), 0.0, 100.0, None),))
    with pytest.raises(SiteFileError, match="no-fly zone 'Goal pad' comes within 0 m"):
        known_zones(zones, FRAME, REGION, 0.5, KEEP)


def test_zones_become_covering_prisms_multipolygon_parts_a_group_outside_zones_dropped() -> None:
    square = _lonlat([(1000.0, 0.0), (1100.0, 100.0), (1000.0, 200.0), (900.0, 100.0)])  # a diamond
    far = _lonlat([(9000.0, 0.0), (9100.0, 0.0), (9100.0, 100.0)])
    parts = (square, _lonlat([(1500.0, 500.0), (1600.0, 500.0), (1600.0, 560.0), (1500.0, 560.0)]))
    zones = GeoZones(
        "z",
        "OGC:CRS84",
        (
            GeoZone("Diamond", (square,), -50.0, 300.0, 0.9),
            GeoZone("Pair", parts, 0.0, 80.0, None),
            GeoZone("Far", (far,), 0, 1, None),
        ),
    )
    out = known_zones(zones, FRAME, REGION, 0.25, KEEP)
    assert [z["name"] for z in out] == ["Diamond", "Pair_1", "Pair_2"]
    diamond = out[0]
    assert diamond["probability"] == 0.9
    assert diamond["z_range"] == [-50.0, 300.0]
    assert diamond["group"] == ""
    np.testing.assert_allclose(diamond["center"], (1000.0, 100.0), atol=0.05)
    assert sorted(diamond["size"]) == pytest.approx([141.42, 141.42], abs=0.05)
    assert abs(diamond["yaw_deg"]) % 90 == pytest.approx(45.0, abs=0.01)
    assert {z["group"] for z in out[1:]} == {"Pair"}
    assert {z["probability"] for z in out[1:]} == {0.25}


def test_masts_on_no_line_become_columns() -> None:
    line = _lonlat([(400.0, -500.0), (900.0, -500.0)])
    way = PowerWay(1, "L", "line", line, (True, True))
    mast = _lonlat([(1200.0, 300.0)])[0]
    outside = _lonlat([(5000.0, 300.0)])[0]
    zones = mast_zones(_power(way, towers=(*line, mast, outside)), FRAME, REGION, KEEP)
    assert len(zones) == 1
    assert zones[0]["radius"] == MAST_RADIUS
    assert zones[0]["probability"] == 1.0
    np.testing.assert_allclose(zones[0]["center"], (1200.0, 300.0), atol=0.01)


def test_a_zone_without_area_is_refused() -> None:
    flat = _lonlat([(1000.0, 0.0), (1100.0, 0.0), (1200.0, 0.0)])
    zones = GeoZones("z", "OGC:CRS84", (GeoZone("Flat", (flat,), 0.0, 100.0, None),))
    with pytest.raises(SiteFileError, match="no-fly zone 'Flat' has no area"):
        known_zones(zones, FRAME, REGION, 0.5, KEEP)
