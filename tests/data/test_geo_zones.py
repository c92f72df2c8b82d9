"""No-fly zones from GeoJSON: properties, parts, CRS, and the files that are refused."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from conftest import REPO_ROOT

from drd_planner.data import geo_zones
from drd_planner.data.geo_zones import read_zones
from drd_planner.exceptions import SiteFileError

ZONES = REPO_ROOT / "sites" / "front_range" / "zones.geojson"
SQUARE = [[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.0, 0.0]]]


def _write(path: Path, data: Any) -> Path:
    path.write_text(json.dumps(data))
    return path


def _collection(*features: Any) -> dict[str, Any]:
    return {"type": "FeatureCollection", "features": list(features)}


def _feature(geometry: Any, **props: Any) -> dict[str, Any]:
    return {"type": "Feature", "properties": props, "geometry": geometry}


def test_the_bundled_zones() -> None:
    zones = read_zones(ZONES)
    assert [z.name for z in zones.zones] == ["Airfield shelf", "Exercise", "Quarry", "Range west"]
    shelf, exercise = zones.zones[0], zones.zones[1]
    assert (shelf.floor_m, shelf.ceiling_m, shelf.p_active) == (90.0, 3000.0, 0.5)
    assert len(exercise.polygons) == 2
    assert exercise.floor_m == -1000.0
    assert exercise.ceiling_m == 10000.0
    assert zones.crs == "OGC:CRS84"


def test_defaults_holes_dropped_and_a_legacy_crs(tmp_path: Path) -> None:
    hole = [[0.2, 0.2], [0.4, 0.2], [0.4, 0.4], [0.2, 0.2]]
    data = _collection(_feature({"type": "Polygon", "coordinates": [SQUARE[0], hole]}))
    data["crs"] = {"type": "name", "properties": {"name": "EPSG:32613"}}
    zones = read_zones(_write(tmp_path / "z.geojson", data))
    (zone,) = zones.zones
    assert zone.name == "zone_0"
    assert zone.p_active is None
    assert len(zone.polygons) == 1
    assert zone.polygons[0] == ((0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0))
    assert zones.crs == "EPSG:32613"


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"type": "Feature"}, "must be a FeatureCollection of Polygon/MultiPolygon features, got 'Feature'"),
        ([1, 2], "must be a FeatureCollection"),
        (_collection(), "'features' must be a non-empty list"),
        (
            _collection(_feature({"type": "Point", "coordinates": [0, 0]})),
            "must be Polygon or MultiPolygon, got 'Point'",
        ),
        (_collection(_feature({"type": "Polygon", "coordinates": [[[0, 0], [1, 0], [0, 0]]]})), "at least 4 positions"),
        (_collection(_feature({"type": "Polygon", "coordinates": [[[0, 0], [1, 0], [1, 1], [0, 1]]]})), "end where"),
        (_collection(_feature({"type": "Polygon", "coordinates": SQUARE}, p_active=1.5)), "p_active must be a prob"),
        (_collection(_feature({"type": "Polygon", "coordinates": SQUARE}, floor_m=50, ceiling_m=20)), "below ceiling"),
        (_collection(_feature({"type": "Polygon", "coordinates": SQUARE}, floor_m="high")), "finite number"),
        (
            _collection(*[_feature({"type": "Polygon", "coordinates": SQUARE}, name="a")] * 2),
            "zone names must be unique",
        ),
    ],
)
def test_malformed_collections_are_refused(tmp_path: Path, data: Any, message: str) -> None:
    with pytest.raises(SiteFileError, match=message):
        read_zones(_write(tmp_path / "z.geojson", data))


def test_not_json_deep_nesting_and_size(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "z.geojson"
    path.write_text("{not json")
    with pytest.raises(SiteFileError, match="is not valid JSON"):
        read_zones(path)
    path.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(SiteFileError, match="is not valid JSON"):
        read_zones(path)
    monkeypatch.setattr(geo_zones, "MAX_GEOJSON_BYTES", 1000)
    with pytest.raises(SiteFileError, match="at most 1000 are read"):
        read_zones(path)
