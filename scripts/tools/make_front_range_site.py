"""Write the bundled site's vector layers: sites/front_range/power.osm and sites/front_range/zones.geojson.

The layers are made up (not OpenStreetMap data): plausible power lines and no-fly zones placed where the
``"corridors"`` model's defaults put its known lines and zones (their lattice-frame routes and footprints,
origin longitude -105.4617, latitude 40.1825, +x north), written in WGS84 longitude/latitude as a user's GIS
export would be. Towers stand about every 300 m, moved by up to 15 m (seeded). Run from the repository root::

    python scripts/tools/make_front_range_site.py [--out sites/front_range]
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from drd_planner.data.geo_frame import SiteFrame

FRAME = SiteFrame(40.1825, -105.4617, 0.0)

#: (name, power tag, voltage, lattice-frame route (m), every node a tower (else only the ends: a
#: pole line whose poles are not mapped), node spacing (m)).
LINES = (
    ("West Feeder", "line", "115000", ((450, -1400), (520, 0), (600, 1400)), True, 300.0),
    ("East Trunk", "line", "230000", ((2200, -1400), (2150, 0), (2250, 1400)), True, 350.0),
    ("Valley Tap", "minor_line", "13800", ((1350, -1400), (1550, -450)), False, 120.0),
    ("Ridge Tap", "minor_line", "13800", ((1300, 1400), (1450, 850)), True, 150.0),
)

#: A mast (a tower on no line), lattice frame (m).
MASTS = ((1900.0, 600.0),)


def _towers(route: np.ndarray, spacing: float, rng: np.random.Generator) -> np.ndarray:
    """Points along ``route`` about ``spacing`` apart, moved by up to 15 m (the ends stay)."""
    if spacing <= 0:
        return route
    out = [route[:1]]
    for a, b in itertools.pairwise(route):
        n = max(1, math.ceil(float(np.linalg.norm(b - a)) / spacing))
        t = np.arange(1, n + 1)[:, None] / n
        out.append(a + t * (b - a))
    pts = np.concatenate(out)
    pts[1:-1] += rng.uniform(-15.0, 15.0, size=pts[1:-1].shape)
    return pts


def _osm(rng: np.random.Generator) -> str:
    nodes: list[str] = []
    ways: list[str] = []
    next_id = 1
    for k, (name, power, voltage, route, all_towers, spacing) in enumerate(LINES):
        pts = _towers(np.asarray(route, dtype=float), spacing, rng)
        lon, lat = FRAME.from_lattice(pts[:, 0], pts[:, 1])
        refs = []
        for j, (x, y) in enumerate(zip(lon, lat, strict=True)):
            tag = all_towers or j in (0, len(lon) - 1)
            kind = "tower" if power == "line" else "pole"
            body = f'<tag k="power" v="{kind}"/>' if tag else ""
            nodes.append(f'  <node id="{next_id}" version="1" lat="{y:.7f}" lon="{x:.7f}">{body}</node>')
            refs.append(next_id)
            next_id += 1
        nds = "".join(f'<nd ref="{r}"/>' for r in refs)
        tags = f'<tag k="power" v="{power}"/><tag k="name" v={quoteattr(name)}/><tag k="voltage" v="{voltage}"/>'
        ways.append(f'  <way id="{100 + k}" version="1">{nds}{tags}</way>')
    for x, y in MASTS:
        lon, lat = FRAME.from_lattice([x], [y])
        nodes.append(
            f'  <node id="{next_id}" version="1" lat="{lat[0]:.7f}" lon="{lon[0]:.7f}">'
            '<tag k="power" v="tower"/><tag k="name" v="Radio mast"/></node>'
        )
        next_id += 1
    body = "\n".join(nodes + ways)
    return f"<?xml version='1.0' encoding='UTF-8'?>\n<osm version=\"0.6\" generator=\"drd_planner\">\n{body}\n</osm>\n"


def _ring(xy: np.ndarray) -> list[list[float]]:
    lon, lat = FRAME.from_lattice(xy[:, 0], xy[:, 1])
    ring = [[round(float(a), 7), round(float(b), 7)] for a, b in zip(lon, lat, strict=True)]
    return ring + ring[:1]


def _rect(cx: float, cy: float, sx: float, sy: float, yaw_deg: float = 0.0) -> list[list[float]]:
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    local = np.array([[-sx, -sy], [sx, -sy], [sx, sy], [-sx, sy]]) / 2
    return _ring(np.array([cx, cy]) + local @ np.array([[c, s], [-s, c]]))


def _circle(cx: float, cy: float, r: float, n: int = 16) -> list[list[float]]:
    t = np.linspace(0, 2 * math.pi, n, endpoint=False)
    return _ring(np.stack([cx + r * np.cos(t), cy + r * np.sin(t)], axis=1))


def _zones() -> dict[str, object]:
    def feature(name: str, geometry: dict[str, object], **props: float) -> dict[str, object]:
        return {"type": "Feature", "properties": {"name": name, **props}, "geometry": geometry}

    return {
        "type": "FeatureCollection",
        "features": [
            feature(
                "Airfield shelf",
                {"type": "Polygon", "coordinates": [_rect(1550, -1000, 1500, 800)]},
                floor_m=90,
                ceiling_m=3000,
                p_active=0.5,
            ),
            feature(
                "Exercise",
                {
                    "type": "MultiPolygon",
                    "coordinates": [[_circle(1000, -950, 220)], [_rect(1850, -1175, 200, 250)]],
                },
                p_active=0.6,
            ),
            feature("Quarry", {"type": "Polygon", "coordinates": [_rect(1700, 1150, 450, 300, 20)]}, p_active=0.4),
            feature("Range west", {"type": "Polygon", "coordinates": [_circle(300, 700, 160)]}, p_active=0.3),
        ],
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default="sites/front_range", help="folder to write to")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "power.osm").write_text(_osm(np.random.default_rng(7)))
    (out / "zones.geojson").write_text(json.dumps(_zones(), indent=1) + "\n")
    print(f"wrote {out / 'power.osm'} and {out / 'zones.geojson'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
