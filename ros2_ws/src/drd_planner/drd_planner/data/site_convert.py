"""Mapped power lines and no-fly zones of a real site, moved into the lattice frame as corridors-model records.

- A power way (:class:`~drd_planner.data.geo_power.PowerWay`) becomes a
  :class:`~drd_planner.domains.helicopter_corridors_params.KnownLine`: its nodes projected into the lattice frame
  (:class:`~drd_planner.data.geo_frame.SiteFrame`) and clipped to the terrain region (the lattice plus the
  world margin; a way that leaves and comes back gives several pieces, ``name``, ``name_2``, ...; a way wholly
  outside is dropped). When every node of the way is a mapped tower, towers stand only there (its span is the
  longest leg); otherwise towers are added at most ``span`` apart as the uncertainty says.
- A tower or pole node on no power way becomes an always-active no-fly column of radius
  :data:`MAST_RADIUS` (a mast whose height is not known).
- A GeoJSON zone (:class:`~drd_planner.data.geo_zones.GeoZone`) becomes one
  :class:`~drd_planner.domains.helicopter_corridors_params.KnownZone` prism per polygon: the polygon's smallest
  rotated rectangle in the lattice frame (it covers the polygon), from ``floor_m`` to ``ceiling_m``; the parts of
  a MultiPolygon are one ``group`` (active together). A zone outside the terrain region is dropped.

Lines and zones that come within ``nofly_keep_clear`` plus the vehicle clearance of the start or goal are
refused here, naming them (the corridors model would refuse them when drawing the first world).

Units: metres in the lattice frame.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from drd_planner.data.geo_frame import WGS84, SiteFrame
from drd_planner.data.geo_power import OsmPower, PowerWay
from drd_planner.data.geo_zones import GeoZones
from drd_planner.exceptions import SiteFileError

__all__ = ["MAST_RADIUS", "LineDefaults", "Region", "known_lines", "known_zones", "mast_zones"]

#: Radius of the no-fly column around a mapped tower that stands on no mapped line (m).
MAST_RADIUS = 15.0

Region = tuple[tuple[float, float], tuple[float, float]]


@dataclass(frozen=True)
class LineDefaults:
    """What is not known of a mapped line (the site file's ``uncertainty``).

    Attributes:
        probability: chance that a mapped line is built and energised (fraction).
        span: [lo, hi] tower spacing (m) where the towers are not all mapped.
        tower_height: [lo, hi] attachment height above the ground (m).
        sag: [lo, hi] sag per span (m).
        conductors: [lo, hi] conductors (count).
    """

    probability: float = 0.8
    span: tuple[float, float] = (250.0, 400.0)
    tower_height: tuple[float, float] = (40.0, 60.0)
    sag: tuple[float, float] = (4.0, 15.0)
    conductors: tuple[int, int] = (1, 3)


def _box(region: Region) -> object:
    """The shapely box of ``region``."""
    from shapely.geometry import box

    (x0, x1), (y0, y1) = region
    return box(x0, y0, x1, y1)


def _pieces(xy: np.ndarray, region: Region) -> list[list[tuple[float, float]]]:
    """The parts of the polyline ``xy`` (k, 2) inside ``region``, each at least 2 points."""
    from shapely.geometry import LineString

    clipped = LineString(xy).intersection(_box(region))
    parts = getattr(clipped, "geoms", [clipped])
    out = []
    for part in parts:
        if part.geom_type == "LineString" and not part.is_empty and part.length > 1.0:
            out.append([(float(x), float(y)) for x, y in part.coords])
    return out


def _keep_clear(what: str, gap: float, need: float) -> None:
    """Refuse a line or zone ``gap`` metres from the start or goal when ``need`` metres are required."""
    if gap < need:
        raise SiteFileError(
            f"{what} comes within {gap:.0f} m of the lattice start or goal; it must keep {need:.0f} m "
            "(nofly_keep_clear plus the vehicle clearance): move the start/goal or the origin, or leave it out"
        )


def known_lines(
    power: OsmPower,
    frame: SiteFrame,
    region: Region,
    defaults: LineDefaults,
    keep: tuple[Sequence[tuple[float, float]], float],
) -> list[dict[str, object]]:
    """The corridors ``lines`` records (dicts) of the mapped power ways (see the module docstring).

    ``keep``: (the start and goal (x, y), the distance lines and zones keep from them) in metres.
    """
    from shapely.geometry import LineString, MultiPoint

    points, need = keep
    keep_points = MultiPoint([tuple(p) for p in points])
    lines: list[dict[str, object]] = []
    names: set[str] = set()
    for way in power.lines:
        lon, lat = np.array(way.points).T
        x, y = frame.to_lattice(lon, lat, WGS84)
        xy = np.stack([x, y], axis=1)
        span = _span(way, xy, defaults)
        for k, route in enumerate(_pieces(xy, region)):
            name = _unique(way.name if k == 0 else f"{way.name}_{k + 1}", way.osm_id, names)
            _keep_clear(f"power line {name!r} (OSM way {way.osm_id})", LineString(route).distance(keep_points), need)
            lines.append(
                {
                    "name": name,
                    "route": [list(p) for p in route],
                    "probability": defaults.probability,
                    "span": list(span),
                    "tower_height": list(defaults.tower_height),
                    "sag": list(defaults.sag),
                    "conductors": list(defaults.conductors),
                }
            )
    return lines


def _span(way: PowerWay, xy: np.ndarray, defaults: LineDefaults) -> tuple[float, float]:
    """The line's span range: its longest leg (plus 1 m) when all its nodes are towers, else the default."""
    if all(way.towers):
        longest = float(np.max(np.hypot(*np.diff(xy, axis=0).T))) + 1.0
        return longest, longest
    return defaults.span


def _unique(name: str, osm_id: int, names: set[str]) -> str:
    """``name``, or ``name_<osm id>`` when taken; recorded in ``names``."""
    out = name if name not in names else f"{name}_{osm_id}"
    while out in names:
        out += "_"
    names.add(out)
    return out


def mast_zones(
    power: OsmPower, frame: SiteFrame, region: Region, keep: tuple[Sequence[tuple[float, float]], float]
) -> list[dict[str, object]]:
    """Always-active no-fly columns around mapped towers on no mapped line, inside ``region`` (zone dicts)."""
    on_lines = {p for way in power.lines for p in way.points}
    alone = [p for p in power.towers if p not in on_lines]
    if not alone:
        return []
    lon, lat = np.array(alone).T
    x, y = frame.to_lattice(lon, lat, WGS84)
    (x0, x1), (y0, y1) = region
    points, need = keep
    out: list[dict[str, object]] = []
    for k, (px, py) in enumerate(zip(x.tolist(), y.tolist(), strict=True)):
        if not (x0 <= px <= x1 and y0 <= py <= y1):
            continue
        gap = min(math.hypot(px - sx, py - sy) for sx, sy in points) - MAST_RADIUS
        _keep_clear(f"mapped tower {k} (not on a mapped line)", gap, need)
        out.append({"name": f"mast_{k}", "center": [px, py], "radius": MAST_RADIUS, "probability": 1.0})
    return out


def known_zones(
    zones: GeoZones,
    frame: SiteFrame,
    region: Region,
    default_probability: float,
    keep: tuple[Sequence[tuple[float, float]], float],
) -> list[dict[str, object]]:
    """The corridors ``zones`` records (dicts) of the GeoJSON zones (see the module docstring)."""
    from shapely.geometry import MultiPoint, Polygon

    points, need = keep
    keep_points = MultiPoint([tuple(p) for p in points])
    area = _box(region)
    out: list[dict[str, object]] = []
    for zone in zones.zones:
        probability = default_probability if zone.p_active is None else zone.p_active
        parts = []
        for ring in zone.polygons:
            gx, gy = np.array(ring).T
            x, y = frame.to_lattice(gx, gy, zones.crs)
            polygon = Polygon(np.stack([x, y], axis=1))
            if polygon.intersects(area):
                parts.append(polygon)
        for k, polygon in enumerate(parts):
            name = zone.name if len(parts) == 1 else f"{zone.name}_{k + 1}"
            if not polygon.area > 1.0:
                raise SiteFileError(f"no-fly zone {name!r} has no area (its polygon is {polygon.area:.2g} m^2)")
            _keep_clear(f"no-fly zone {name!r}", polygon.distance(keep_points), need)
            out.append(
                {
                    "name": name,
                    "shape": "prism",
                    **_rectangle(polygon),
                    "z_range": [zone.floor_m, zone.ceiling_m],
                    "probability": probability,
                    "group": zone.name if len(parts) > 1 else "",
                }
            )
    return out


def _rectangle(polygon: object) -> dict[str, object]:
    """``center``, ``size`` and ``yaw_deg`` of the smallest rotated rectangle around ``polygon``."""
    from shapely import minimum_rotated_rectangle

    corners = np.asarray(minimum_rotated_rectangle(polygon).exterior.coords)[:4]
    centre = corners.mean(axis=0)
    a, b = corners[1] - corners[0], corners[2] - corners[1]
    size = (max(float(np.hypot(*a)), 1.0), max(float(np.hypot(*b)), 1.0))
    yaw = math.degrees(math.atan2(float(a[1]), float(a[0])))
    return {"center": [float(centre[0]), float(centre[1])], "size": list(size), "yaw_deg": yaw}
