"""The ``"corridors"`` helicopter world model: one real operating site, its known power lines and no-fly zones.

What a real operator has, and what stays uncertain from flight to flight
(:class:`~drd_planner.domains.helicopter_corridors_params.CorridorsParams`):

- **terrain**: the site's elevation model (an ESRI ASCII grid or a GeoTIFF, e.g. SRTM at ~90 m) at its true
  scale, with its registration error. The world's terrain is the DEM shifted horizontally by a random (dx, dy) and
  vertically by a random bias (Gaussian, ``shift_sigma`` / ``bias_sigma``, clipped at 3 sigma), sampled
  bilinearly on the frame's terrain grid; z = 0 is the ``datum`` (default: the DEM's height at the lattice
  origin). Within ``keep_clear_radius`` of the start and goal it is capped below them (a pad).
- **power lines** on known routes (:class:`~drd_planner.domains.helicopter_corridors_params.KnownLine`):
  each is present (built and energised) with its ``probability``; its tower spacing (at most ``span``,
  towers evenly spaced on every route leg), tower height above the (true) ground, each tower's jitter,
  the number of conductors and every span's sag are drawn per world.
- **no-fly zones** from a published list
  (:class:`~drd_planner.domains.helicopter_corridors_params.KnownZone`), each active with its ``probability``.
- **what is missing from the map** (off by default): ``unmapped_lines`` straight power lines across the
  lattice's extent at random places and bearings, and ``unmapped_towers`` lone towers, their numbers drawn per
  world, each kept clear of the start and goal (left out after 20 tries). They are drawn after everything
  else, and only when asked for, so the other draws of a seed do not change.

Every line and zone is drawn in every world (present or not), so the same seed gives the same numbers
whatever the others do. Known routes and zones that come within ``nofly_keep_clear`` (plus the vehicle
clearance) of the start or goal are refused, so the start and goal are free in every world.

Units: metres, degrees where the name says ``_deg``.
"""

from __future__ import annotations

import itertools
import math
from typing import Any, NamedTuple

import numpy as np
from scipy.ndimage import map_coordinates

from drd_planner.arrays import FloatArray
from drd_planner.domains.helicopter_corridors_params import CorridorsParams, KnownLine
from drd_planner.domains.helicopter_terrain_model import TerrainGrids
from drd_planner.domains.helicopter_world_frame import (
    ModelDraw,
    WorldFrame,
    draw_integer,
    draw_uniform,
    flatten_near,
)
from drd_planner.domains.helicopter_world_params import NoFlyZone
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Cylinder, Shape
from drd_planner.geometry.terrain import Heightfield
from drd_planner.geometry.wires import Wire

__all__ = ["CorridorsModel", "SiteGrid", "metres_per_degree"]


def metres_per_degree(latitude_deg: float) -> tuple[float, float]:
    """(east, north) metres per degree of longitude and latitude at ``latitude_deg`` (WGS84 series)."""
    phi = math.radians(latitude_deg)
    north = 111_132.954 - 559.822 * math.cos(2 * phi) + 1.175 * math.cos(4 * phi)
    east = 111_412.84 * math.cos(phi) - 93.5 * math.cos(3 * phi) + 0.118 * math.cos(5 * phi)
    return east, north


class SiteGrid:
    """The elevation grid seen from the lattice frame: DEM heights at lattice (x, y), metres.

    Args:
        grid: the elevation grid (its own coordinates: degrees or metres).
        p: the model's parameters (units, site origin and heading).
    """

    def __init__(self, grid: Heightfield, p: CorridorsParams) -> None:
        self.grid = grid
        self.origin = p.site_origin
        if p.grid_units == "degrees":
            self.per_unit = metres_per_degree(p.site_origin[1])
        else:
            self.per_unit = (1.0, 1.0)
        theta = math.radians(p.site_heading_deg)
        self.cos, self.sin = math.cos(theta), math.sin(theta)

    def heights(self, x: FloatArray, y: FloatArray) -> FloatArray:
        """DEM heights at lattice-frame points (any shape), bilinear; NaN outside the grid or on NODATA."""
        east = self.cos * np.asarray(x) - self.sin * np.asarray(y)
        north = self.sin * np.asarray(x) + self.cos * np.asarray(y)
        gx = self.origin[0] + east / self.per_unit[0]
        gy = self.origin[1] + north / self.per_unit[1]
        ox, oy = (float(v) for v in self.grid.origin)
        cell = float(self.grid.cell_size)
        coords = np.stack([(gy - oy) / cell, (gx - ox) / cell])
        return np.asarray(
            map_coordinates(self.grid.heights, coords, order=1, mode="constant", cval=np.nan),
            dtype=np.float64,
        )


class _Registration(NamedTuple):
    """The DEM's registration error in one world: horizontal shift (dx, dy) and vertical bias, metres."""

    dx: float
    dy: float
    bias: float


def _clipped_normal(rng: np.random.Generator, sigma: float) -> float:
    """A normal draw of standard deviation ``sigma`` clipped to +-3 sigma (0 without drawing for sigma 0)."""
    return float(np.clip(rng.normal(0.0, sigma), -3 * sigma, 3 * sigma)) if sigma > 0 else 0.0


class _TrueTerrain:
    """The world's terrain as a function: the DEM shifted by the registration error, minus the datum."""

    def __init__(self, site: SiteGrid, reg: _Registration, datum: float) -> None:
        self.site, self.reg, self.datum = site, reg, datum

    def __call__(self, x: FloatArray, y: FloatArray) -> FloatArray:
        """Heights (metres above the datum) at lattice-frame points (any shape)."""
        raw = self.site.heights(np.asarray(x) + self.reg.dx, np.asarray(y) + self.reg.dy)
        return np.asarray(raw - self.datum + self.reg.bias, dtype=np.float64)


def _distance_to_route(points: FloatArray, route: FloatArray) -> FloatArray:
    """(p,) horizontal distance of each (p, >= 2) point to the polyline ``route`` (k, 2), metres."""
    xy = points[:, None, :2]
    a, b = route[None, :-1], route[None, 1:]
    ab = b - a
    t = np.clip(np.sum((xy - a) * ab, axis=2) / np.maximum(np.sum(ab * ab, axis=2), 1e-12), 0.0, 1.0)
    nearest = a + t[..., None] * ab
    return np.asarray(np.linalg.norm(xy - nearest, axis=2).min(axis=1), dtype=np.float64)


def _footprint_gap(zone: NoFlyZone, points: FloatArray) -> FloatArray:
    """(p,) horizontal distance of each (p, >= 2) point to the zone's footprint (0 inside), metres."""
    d = points[:, :2] - np.asarray(zone.center)
    if zone.shape == "cylinder":
        return np.asarray(np.maximum(np.hypot(d[:, 0], d[:, 1]) - zone.radius, 0.0), dtype=np.float64)
    c, s = math.cos(math.radians(zone.yaw_deg)), math.sin(math.radians(zone.yaw_deg))
    out_x = np.maximum(np.abs(c * d[:, 0] + s * d[:, 1]) - zone.size[0] / 2, 0.0)
    out_y = np.maximum(np.abs(-s * d[:, 0] + c * d[:, 1]) - zone.size[1] / 2, 0.0)
    return np.asarray(np.hypot(out_x, out_y), dtype=np.float64)


def _check_keep_clear(p: CorridorsParams, frame: WorldFrame) -> None:
    """ProblemError naming the known line or zone that comes too close to the start or goal."""
    keep = np.asarray(frame.keep_clear, dtype=np.float64).reshape(-1, 3)
    if keep.size == 0:
        return
    need = p.nofly_keep_clear + frame.clearance
    for line in p.lines:
        gap = float(_distance_to_route(keep, np.asarray(line.route)).min())
        if gap < need:
            raise ProblemError(
                f"known line {line.name!r} passes {gap:.0f} m from the start or goal; it must keep {need:.0f} m "
                "(models.corridors.nofly_keep_clear plus the vehicle clearance): move its route or drop it"
            )
    for zone in p.zones:
        gap = float(_footprint_gap(zone, keep).min())
        if gap < need:
            raise ProblemError(
                f"known no-fly zone {zone.name!r} comes within {gap:.0f} m of the "
                f"start or goal; it must keep {need:.0f} m (models.corridors.nofly_keep_clear plus the vehicle "
                "clearance): move or shrink it, or drop it"
            )


def _towers(route: FloatArray, span: float) -> FloatArray:
    """(n, 2) tower positions: every route point and evenly spaced between, at most ``span`` metres apart."""
    out = [route[:1]]
    for a, b in itertools.pairwise(route):
        pieces = max(1, math.ceil(float(np.linalg.norm(b - a)) / span - 1e-9))
        t = np.arange(1, pieces + 1)[:, None] / pieces
        out.append(a + t * (b - a))
    return np.concatenate(out)


class _LineDraw(NamedTuple):
    """What is drawn for one known line in every world (present or not)."""

    present: bool
    span: float
    height: float
    conductors: int
    jitter: FloatArray
    sags: FloatArray


def _draw_line(rng: np.random.Generator, line: KnownLine, jitter: float) -> _LineDraw:
    """Presence, span, height, conductors, per-tower jitter and per-span sag of ``line``."""
    present = bool(rng.random() < line.probability)
    span = draw_uniform(rng, line.span)
    height = draw_uniform(rng, line.tower_height)
    conductors = draw_integer(rng, line.conductors)
    n = _towers(np.asarray(line.route), span).shape[0]
    return _LineDraw(
        present,
        span,
        height,
        conductors,
        np.asarray(rng.uniform(-jitter, jitter, size=n), dtype=np.float64),
        np.asarray(rng.uniform(line.sag[0], line.sag[1], size=n - 1), dtype=np.float64),
    )


def _draw_lines(rng: np.random.Generator, p: CorridorsParams) -> list[_LineDraw]:
    """Every known line's draw; a line whose ``requires`` line is absent is absent too."""
    draws: dict[str, _LineDraw] = {}
    for line in p.lines:
        drawn = _draw_line(rng, line, p.tower_jitter)
        if line.requires and not draws[line.requires].present:
            drawn = drawn._replace(present=False)
        draws[line.name] = drawn
    return list(draws.values())


def _draw_zones(rng: np.random.Generator, p: CorridorsParams) -> list[bool]:
    """Whether each known zone is active; zones of one group follow the draw of its first zone."""
    group_state: dict[str, bool] = {}
    active: list[bool] = []
    for zone in p.zones:
        on = bool(rng.random() < zone.probability)
        if zone.group:
            on = group_state.setdefault(zone.group, on)
        active.append(on)
    return active


def _line_parts(
    line: KnownLine, drawn: _LineDraw, ground: _TrueTerrain, p: CorridorsParams
) -> tuple[list[Wire], list[tuple[str, Shape, Pose]]]:
    """The towers (cylinders from 10 m under the ground to the top) and conductors of a present line."""
    bases = _towers(np.asarray(line.route), drawn.span)
    z0 = ground(bases[:, 0], bases[:, 1])
    if np.isnan(z0).any():
        raise ProblemError(
            f"known line {line.name!r} has towers outside the elevation grid; shorten its route or move "
            "models.corridors.site_origin"
        )
    tops = z0 + drawn.height + drawn.jitter
    solids: list[tuple[str, Shape, Pose]] = []
    for k in range(bases.shape[0]):
        length = float(tops[k] - z0[k]) + 10.0
        centre = (float(bases[k, 0]), float(bases[k, 1]), float(z0[k]) - 10.0 + length / 2.0)
        solids.append((f"tower_{line.name}_{k}", Cylinder(p.tower_radius, length), Pose(centre)))
    wires: list[Wire] = []
    for k in range(bases.shape[0] - 1):
        for c in range(drawn.conductors):
            dz = c * p.conductor_gap
            a = (float(bases[k, 0]), float(bases[k, 1]), float(tops[k]) - dz)
            b = (float(bases[k + 1, 0]), float(bases[k + 1, 1]), float(tops[k + 1]) - dz)
            wires.append(Wire(a, b, float(drawn.sags[k]), p.wire_diameter))
    return wires, solids


def _terrain(truth: _TrueTerrain, p: CorridorsParams, frame: WorldFrame) -> FloatArray:
    """(rows, cols) world terrain on the frame's grid (pads at the start and goal applied), metres."""
    xs, ys = frame.grid()
    gx, gy = np.meshgrid(xs, ys)
    heights = truth(gx, gy)
    if np.isnan(heights).any():
        raise ProblemError(
            f"the corridors site (origin {p.site_origin}, heading {p.site_heading_deg} deg) leaves the elevation "
            f"grid or meets NODATA cells for a frame of x {frame.x_range}, y {frame.y_range} plus "
            f"{frame.margin} m; move models.corridors.site_origin or shrink the lattice"
        )
    keep = np.asarray(frame.keep_clear, dtype=np.float64).reshape(-1, 3)
    if keep.size:
        cap = float(keep[:, 2].min()) - frame.clearance - p.ground_gap
        heights = flatten_near(heights, gx, gy, keep, cap=cap, radius=p.keep_clear_radius)
    return heights


class CorridorsModel:
    """The ``"corridors"`` world model; it owns (or shares) the cache of the elevation grids it reads."""

    def __init__(self, grids: TerrainGrids | None = None) -> None:
        self.grids = TerrainGrids() if grids is None else grids

    def site(self, p: CorridorsParams) -> SiteGrid:
        """The site's view of its elevation grid.

        Raises:
            ProblemError: the grid file is missing or unusable, or its CRS is not measured in ``grid_units``.
        """
        path = p.resolved_path()
        grid = self.grids.load(path)
        units = self.grids.units(path)
        if units is not None and units != p.grid_units:
            raise ProblemError(
                f"the elevation grid {path} is measured in {units} (its CRS) but models.corridors.grid_units is "
                f"{p.grid_units!r}; set grid_units to {units!r} and site_origin in the grid's coordinates"
            )
        return SiteGrid(grid, p)

    def draw(self, rng: np.random.Generator, p: CorridorsParams, frame: WorldFrame) -> ModelDraw:
        """One world of the site: registered terrain, the present lines and the active zones.

        Raises:
            ProblemError: missing grid, a site leaving the grid, or a known line or zone too close to the start
                or goal.
        """
        _check_keep_clear(p, frame)
        site = self.site(p)
        datum = p.datum if p.datum is not None else float(site.heights(np.zeros(1), np.zeros(1))[0])
        if not math.isfinite(datum):
            raise ProblemError(
                f"the corridors site origin {p.site_origin} lies outside the elevation grid; move "
                "models.corridors.site_origin"
            )
        reg = _Registration(
            _clipped_normal(rng, p.shift_sigma),
            _clipped_normal(rng, p.shift_sigma),
            _clipped_normal(rng, p.bias_sigma),
        )
        truth = _TrueTerrain(site, reg, datum)
        heights = _terrain(truth, p, frame)
        draws = _draw_lines(rng, p)
        active = _draw_zones(rng, p)
        wires: list[Wire] = []
        solids: list[tuple[str, Shape, Pose]] = []
        for line, drawn in zip(p.lines, draws, strict=True):
            if drawn.present:
                more_wires, more_solids = _line_parts(line, drawn, truth, p)
                wires.extend(more_wires)
                solids.extend(more_solids)
        zones = tuple(zone.column() for zone, on in zip(p.zones, active, strict=True) if on)
        info = _summary(p, reg, datum, draws, active)
        if p.unmapped_lines[1] > 0 or p.unmapped_towers[1] > 0:  # no draw otherwise: other worlds keep their numbers
            more_wires, more_solids, info["unmapped"] = _unmapped(rng, p, frame, truth)
            wires.extend(more_wires)
            solids.extend(more_solids)
        return ModelDraw(frame.heightfield(heights), tuple(wires), tuple(solids), info, zones)


#: Tries to place an unmapped line or tower clear of the start and goal before it is left out of the world.
_UNMAPPED_TRIES = 20


def _chord(centre: FloatArray, theta: float, box: tuple[tuple[float, float], tuple[float, float]]) -> FloatArray:
    """(2, 2) ends of the line through ``centre`` (inside ``box``) at angle ``theta`` rad, cut at the box's edges."""
    u = np.array([math.cos(theta), math.sin(theta)])
    lo, hi = -math.inf, math.inf
    for axis, (a, b) in enumerate(box):
        if abs(u[axis]) > 1e-12:
            t1, t2 = (a - centre[axis]) / u[axis], (b - centre[axis]) / u[axis]
            lo, hi = max(lo, min(t1, t2)), min(hi, max(t1, t2))
    return np.stack([centre + lo * u, centre + hi * u])


def _unmapped(
    rng: np.random.Generator, p: CorridorsParams, frame: WorldFrame, ground: _TrueTerrain
) -> tuple[list[Wire], list[tuple[str, Shape, Pose]], dict[str, Any]]:
    """Power lines and lone towers missing from the map, inside the lattice's extent and clear of the start/goal.

    Returns the wires, the solids (towers) and the summary (each line's ends, each tower's place and height).
    """
    box = (frame.x_range, frame.y_range)
    keep = np.asarray(frame.keep_clear, dtype=np.float64).reshape(-1, 3)
    need = p.nofly_keep_clear + frame.clearance
    wires: list[Wire] = []
    solids: list[tuple[str, Shape, Pose]] = []
    summary: dict[str, Any] = {"lines": [], "towers": []}
    for k in range(draw_integer(rng, p.unmapped_lines)):
        for _try in range(_UNMAPPED_TRIES):
            centre = np.array([rng.uniform(*box[0]), rng.uniform(*box[1])])
            route = _chord(centre, rng.uniform(0.0, math.pi), box)
            if not keep.size or float(_distance_to_route(keep, route).min()) >= need:
                break
        else:
            continue
        line = KnownLine(
            f"unmapped_line_{k}",
            tuple(map(tuple, route)),
            1.0,
            p.unmapped_line.span,
            p.unmapped_line.tower_height,
            p.unmapped_line.sag,
            p.unmapped_line.conductors,
        )
        more_wires, more_solids = _line_parts(line, _draw_line(rng, line, p.tower_jitter), ground, p)
        wires.extend(more_wires)
        solids.extend(more_solids)
        summary["lines"].append(route.tolist())
    for k in range(draw_integer(rng, p.unmapped_towers)):
        for _try in range(_UNMAPPED_TRIES):
            xy = np.array([rng.uniform(*box[0]), rng.uniform(*box[1])])
            if not keep.size or float(np.hypot(*(keep[:, :2] - xy).T).min()) - p.tower_radius >= need:
                break
        else:
            continue
        height = draw_uniform(rng, p.unmapped_line.tower_height)
        z0 = float(ground(xy[:1], xy[1:])[0])
        if not math.isfinite(z0):
            raise ProblemError(f"an unmapped tower at {xy.tolist()} stands outside the elevation grid")
        axis = (float(xy[0]), float(xy[1]), z0 - 10.0 + (height + 10.0) / 2.0)
        solids.append((f"tower_lone_{k}", Cylinder(p.tower_radius, height + 10.0), Pose(axis)))
        summary["towers"].append([float(xy[0]), float(xy[1]), height])
    return wires, solids, summary


def _summary(
    p: CorridorsParams, reg: _Registration, datum: float, draws: list[_LineDraw], active: list[bool]
) -> dict[str, Any]:
    """The JSON-able summary of one draw: registration, datum, each line's draw and each zone's state."""
    return {
        "datum": datum,
        "registration": {"dx": reg.dx, "dy": reg.dy, "bias": reg.bias},
        "lines": [
            {
                "name": line.name,
                "present": d.present,
                "span": d.span,
                "tower_height": d.height,
                "conductors": d.conductors,
            }
            for line, d in zip(p.lines, draws, strict=True)
        ],
        "zones": [{"name": zone.name, "active": on} for zone, on in zip(p.zones, active, strict=True)],
    }
