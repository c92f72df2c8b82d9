"""Published no-fly zones from a GeoJSON file: a FeatureCollection of Polygon or MultiPolygon features.

Each feature's properties (all optional):

============== ============================================================================================
``name``       label (default ``zone_<index>``); names must be unique
``floor_m``    bottom of the zone, metres above the site's height datum (default: -1000, from below ground)
``ceiling_m``  top of the zone, metres above the site's height datum (default: 10000); above ``floor_m``
``p_active``   chance that the zone is active in a world, in [0, 1] (default: the site file's
               ``uncertainty.zone_probability``)
============== ============================================================================================

Other properties are ignored. Coordinates are WGS84 longitude/latitude (RFC 7946); a legacy top-level ``crs``
member naming another CRS (e.g. ``urn:ogc:def:crs:EPSG::32613``) is honoured. Limits: the file's bytes
(:data:`MAX_GEOJSON_BYTES`, looked at before reading), its nesting and its vertices (:data:`MAX_ZONE_VERTICES`).

Units: the CRS's (degrees for WGS84), metres for floors and ceilings.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from drd_planner.bounded_files import read_bounded_text
from drd_planner.exceptions import SiteFileError

__all__ = ["MAX_GEOJSON_BYTES", "MAX_ZONE_VERTICES", "GeoZone", "GeoZones", "read_zones"]

#: Largest GeoJSON file read, bytes.
MAX_GEOJSON_BYTES = 8 << 20

#: Most polygon vertices in one GeoJSON file.
MAX_ZONE_VERTICES = 200_000

#: Defaults of a zone's floor and ceiling (metres above the site's datum).
DEFAULT_FLOOR_M = -1000.0
DEFAULT_CEILING_M = 10000.0

Ring = tuple[tuple[float, float], ...]


@dataclass(frozen=True)
class GeoZone:
    """One no-fly zone of the file.

    Attributes:
        name: its label.
        polygons: its parts, each the exterior ring's (x, y) vertices in the file's CRS (holes are dropped:
            the zone keeps out of them too).
        floor_m: bottom above the site's datum (m).
        ceiling_m: top above the site's datum (m).
        p_active: chance that it is active, or None: the site's default.
    """

    name: str
    polygons: tuple[Ring, ...]
    floor_m: float
    ceiling_m: float
    p_active: float | None


@dataclass(frozen=True)
class GeoZones:
    """The zones of one GeoJSON file.

    Attributes:
        path: the file (absolute).
        crs: the CRS of its coordinates (pyproj-readable text).
        zones: the zones in file order.
    """

    path: str
    crs: str
    zones: tuple[GeoZone, ...]


def _number(props: Mapping[str, Any], key: str, default: float | None, where: str) -> float | None:
    """The finite number ``props[key]`` (``default`` when absent or null)."""
    value = props.get(key)
    if value is None:
        return default
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise SiteFileError(f"{where}: property {key!r} must be a finite number, got {value!r}")
    return float(value)


def _ring(value: Any, where: str) -> Ring:
    """A closed ring's vertices (the closing repeat dropped), at least 3."""
    if not isinstance(value, list) or len(value) < 4:
        raise SiteFileError(f"{where}: a polygon ring must be a list of at least 4 positions, got {value!r:.80}")
    out: list[tuple[float, float]] = []
    for pos in value:
        ok = isinstance(pos, list) and len(pos) in (2, 3)
        ok = ok and all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in pos)
        if not ok:
            raise SiteFileError(f"{where}: a position must be [x, y] (or [x, y, z]) finite numbers, got {pos!r:.80}")
        out.append((float(pos[0]), float(pos[1])))
    if out[0] != out[-1]:
        raise SiteFileError(f"{where}: a polygon ring must end where it starts (RFC 7946)")
    return tuple(out[:-1])


def _polygons(geometry: Any, where: str) -> tuple[Ring, ...]:
    """The exterior rings of a Polygon or MultiPolygon geometry."""
    if not isinstance(geometry, Mapping):
        raise SiteFileError(f"{where}: a feature needs a geometry object, got {geometry!r:.80}")
    kind, coords = geometry.get("type"), geometry.get("coordinates")
    if kind == "Polygon":
        parts = [coords]
    elif kind == "MultiPolygon" and isinstance(coords, list):
        parts = coords
    else:
        raise SiteFileError(f"{where}: geometry type must be Polygon or MultiPolygon, got {kind!r}")
    rings = []
    for part in parts:
        if not isinstance(part, list) or not part:
            raise SiteFileError(f"{where}: a polygon must be a list of rings, got {part!r:.80}")
        rings.append(_ring(part[0], where))
    if not rings:
        raise SiteFileError(f"{where}: a MultiPolygon needs at least one polygon")
    return tuple(rings)


def _zone(index: int, feature: Any, path: Path) -> GeoZone:
    """The zone of feature ``index``."""
    where = f"GeoJSON {path} feature {index}"
    if not isinstance(feature, Mapping) or feature.get("type") != "Feature":
        raise SiteFileError(f"{where}: must be an object of type 'Feature'")
    props = feature.get("properties") or {}
    if not isinstance(props, Mapping):
        raise SiteFileError(f"{where}: properties must be an object")
    name = props.get("name", f"zone_{index}")
    if not isinstance(name, str) or not name:
        raise SiteFileError(f"{where}: property 'name' must be a non-empty string, got {name!r}")
    where = f"GeoJSON {path} zone {name!r}"
    floor = _number(props, "floor_m", DEFAULT_FLOOR_M, where)
    ceiling = _number(props, "ceiling_m", DEFAULT_CEILING_M, where)
    assert floor is not None and ceiling is not None
    if not floor < ceiling:
        raise SiteFileError(f"{where}: floor_m {floor:g} must be below ceiling_m {ceiling:g}")
    p_active = _number(props, "p_active", None, where)
    if p_active is not None and not 0.0 <= p_active <= 1.0:
        raise SiteFileError(f"{where}: p_active must be a probability in [0, 1], got {p_active:g}")
    return GeoZone(name, _polygons(feature.get("geometry"), where), floor, ceiling, p_active)


def _crs(data: Mapping[str, Any], path: Path) -> str:
    """The CRS of the file's coordinates: WGS84 longitude/latitude, or a legacy ``crs`` member's name."""
    legacy = data.get("crs")
    if legacy is None:
        return "OGC:CRS84"
    name = legacy.get("properties", {}).get("name") if isinstance(legacy, Mapping) else None
    if not isinstance(name, str):
        raise SiteFileError(f"GeoJSON {path}: a 'crs' member must be {{'type': 'name', 'properties': {{'name': ...}}}}")
    return name


def read_zones(path: str | Path) -> GeoZones:
    """The no-fly zones of the GeoJSON file at ``path`` (see the module docstring).

    Raises:
        SiteFileError: a file too large, not JSON, too deeply nested, not a FeatureCollection of Polygon or
            MultiPolygon features, with no features, too many vertices, duplicate names or bad properties.
    """
    file = Path(path).resolve()
    text = read_bounded_text(file, MAX_GEOJSON_BYTES, f"GeoJSON {file}", SiteFileError)
    try:
        data = json.loads(text)
    except (json.JSONDecodeError, RecursionError) as exc:
        raise SiteFileError(f"GeoJSON {file} is not valid JSON ({type(exc).__name__}: {exc})") from None
    if not isinstance(data, Mapping) or data.get("type") != "FeatureCollection":
        kind = data.get("type") if isinstance(data, Mapping) else type(data).__name__
        raise SiteFileError(
            f"GeoJSON {file} must be a FeatureCollection of Polygon/MultiPolygon features, got {kind!r}"
        )
    features = data.get("features")
    if not isinstance(features, list) or not features:
        raise SiteFileError(f"GeoJSON {file}: 'features' must be a non-empty list")
    zones = tuple(_zone(i, f, file) for i, f in enumerate(features))
    vertices = sum(len(ring) for zone in zones for ring in zone.polygons)
    if vertices > MAX_ZONE_VERTICES:
        raise SiteFileError(f"GeoJSON {file} has {vertices} polygon vertices; at most {MAX_ZONE_VERTICES}")
    names = [z.name for z in zones]
    if len(set(names)) != len(names):
        raise SiteFileError(f"GeoJSON {file}: zone names must be unique, got {names}")
    return GeoZones(str(file), _crs(data, file), zones)
