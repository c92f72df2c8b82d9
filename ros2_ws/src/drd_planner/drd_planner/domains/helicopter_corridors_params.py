"""The parameters of the ``"corridors"`` helicopter world model: one real operating site and what is known of it.

An operator knows the site's elevation model (a DEM, e.g. SRTM, with its registration error), the routes of
the power lines across it (:class:`KnownLine`; whether each is built and energised, its tower spacing and
heights and the wires' sag are not known) and the published no-fly zones (:class:`KnownZone`; each is
active or not). :class:`CorridorsParams` holds them; the model is
:mod:`~drd_planner.domains.helicopter_corridors_model`.

The defaults are one site of the shared SRTM Front Range grid (longitude -105.4617, latitude 40.1825, the
lattice's x axis pointing north): a massif in the middle, a valley east and south of it; four known lines
(two taps that stand only where their line does) and five known zones (an airspace shelf over the valley and
two areas of one exercise that are activated together), laid out for the real-scale lattice
``trees/heli_lines_spec.json`` (x in [0, 2500] m, y in [-1250, 1250] m, start (0, 0), goal (2500, -1000),
60 m above the datum); they also keep clear of the default lattice's start and goal.

Units: metres, degrees where the name says ``_deg``; probabilities in [0, 1].
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from drd_planner.domains.helicopter_params import check_range, params_from_dict
from drd_planner.domains.helicopter_world_params import NoFlyParams, NoFlyZone, Range, default_terrain_path
from drd_planner.exceptions import ProblemError

__all__ = ["GRID_UNITS", "CorridorsParams", "KnownLine", "KnownZone"]

#: How the elevation grid's coordinates are measured: geographic degrees or projected metres.
GRID_UNITS: tuple[str, ...] = ("degrees", "metres")


def _probability(value: Any, what: str) -> float:
    """``value`` as a float in [0, 1], else ProblemError naming ``what``."""
    number = float(value) if isinstance(value, int | float) and not isinstance(value, bool) else math.nan
    if not 0.0 <= number <= 1.0:
        raise ProblemError(f"{what} must be a probability in [0, 1], got {value!r}")
    return number


def _finite_pairs(value: Any, what: str, *, minimum: int) -> tuple[tuple[float, float], ...]:
    """``value`` as at least ``minimum`` finite (x, y) pairs, else ProblemError."""
    try:
        pairs = tuple((float(p[0]), float(p[1])) for p in value)
        ok = all(len(p) == 2 for p in value)
    except (TypeError, ValueError, IndexError):
        raise ProblemError(f"{what} must be a list of [x, y] points, got {value!r}") from None
    if not ok or len(pairs) < minimum or not np.isfinite(np.asarray(pairs)).all():
        raise ProblemError(f"{what} must be at least {minimum} finite [x, y] points, got {value!r}")
    return pairs


def _finite(value: Any, what: str) -> float:
    """``value`` as a finite float, else ProblemError naming ``what``."""
    number = float(value) if isinstance(value, int | float) and not isinstance(value, bool) else math.nan
    if not math.isfinite(number):
        raise ProblemError(f"{what} must be a finite number, got {value!r}")
    return number


def _positive(value: Any, what: str, *, zero: bool = False) -> float:
    """``value`` as a finite float > 0 (>= 0 with ``zero``), else ProblemError."""
    number = float(value) if isinstance(value, int | float) and not isinstance(value, bool) else math.nan
    if not (math.isfinite(number) and (number >= 0.0 if zero else number > 0.0)):
        raise ProblemError(f"{what} must be finite and {'>=' if zero else '>'} 0, got {value!r}")
    return number


@dataclass(frozen=True)
class KnownLine:
    """A power line on a known route; whether it stands and how it hangs are drawn per world.

    Attributes:
        name: label of the line (name), used in collision part names and error messages.
        route: (x, y) route points in the lattice frame (m); at least 2 ( a tower stands on every point and
            evenly between them).
        probability: chance that the line is built and energised in a world (fraction).
        span: [lo, hi] largest tower spacing along the route (m), drawn once per line and world).
        tower_height: [lo, hi] height of the top conductor's attachment above the ground (m), drawn
            once per line and world; each tower adds the model's ``tower_jitter``.
        sag: [lo, hi] sag of the wire below the chord at mid-span (m), drawn per span.
        conductors: [lo, hi] number of conductors (count), one above the other ``conductor_gap`` apart.
        requires: a line listed before this one that it branches from (name), "" for none: this line
            stands only where that one does, and then with ``probability`` (a tap needs its trunk).
    """

    name: str = "line"
    route: tuple[tuple[float, float], ...] = ((500.0, -1300.0), (500.0, 1300.0))
    probability: float = 0.5
    span: Range = (250.0, 400.0)
    tower_height: Range = (40.0, 60.0)
    sag: Range = (4.0, 15.0)
    conductors: tuple[int, int] = (1, 3)
    requires: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ProblemError(f"known line name must be a non-empty string, got {self.name!r}")
        if not isinstance(self.requires, str) or self.requires == self.name:
            raise ProblemError(f"known line {self.name!r} requires must name another line, got {self.requires!r}")
        label = f"known line {self.name!r}"
        object.__setattr__(self, "route", _finite_pairs(self.route, f"{label} route", minimum=2))
        object.__setattr__(self, "probability", _probability(self.probability, f"{label} probability"))
        object.__setattr__(self, "span", check_range(self.span, f"{label} span", low=1.0))
        object.__setattr__(self, "tower_height", check_range(self.tower_height, f"{label} tower_height", low=0.0))
        object.__setattr__(self, "sag", check_range(self.sag, f"{label} sag", low=0.0))
        object.__setattr__(self, "conductors", check_range(self.conductors, f"{label} conductors", low=1, integer=True))


@dataclass(frozen=True)
class KnownZone(NoFlyZone):
    """A published no-fly zone (a vertical column) that is active in a world with a probability.

    Attributes:
        shape: "cylinder" or "prism", a rectangular prism (name).
        center: (x, y) of its axis in the lattice frame (m).
        radius: cylinder radius (m), cylinders only.
        size: (x, y) side lengths of the prism before its yaw (m), prisms only.
        yaw_deg: prism rotation about z (deg).
        z_range: (bottom, top) in the world frame (m); z = 0 at the model's datum.
        name: label of the zone (name), used in error messages and the draw's summary.
        probability: chance that the zone is active in a world (fraction).
        group: zones with the same non-empty group (name) are activated together, one draw per group (e.g. the
            areas of one exercise or one NOTAM); they must have the same ``probability``.
    """

    name: str = "zone"
    probability: float = 0.5
    group: str = ""

    def __post_init__(self) -> None:
        super().__post_init__()
        if not isinstance(self.name, str) or not self.name:
            raise ProblemError(f"known zone name must be a non-empty string, got {self.name!r}")
        object.__setattr__(self, "probability", _probability(self.probability, f"known zone {self.name!r} probability"))
        if not isinstance(self.group, str):
            raise ProblemError(f"known zone {self.name!r} group must be a string, got {self.group!r}")

    def column(self) -> NoFlyZone:
        """The zone as a plain :class:`NoFlyZone` (what an active zone adds to a world)."""
        return NoFlyZone(self.shape, self.center, self.radius, self.size, self.yaw_deg, self.z_range)


def _records(value: Any, cls: type[Any], what: str) -> tuple[Any, ...]:
    """A tuple of ``cls`` records from records or dicts, else ProblemError."""
    if not isinstance(value, (list, tuple)):
        raise ProblemError(f"{what} must be a list of {cls.__name__} dicts, got {value!r}")
    out = tuple(item if isinstance(item, cls) else params_from_dict(cls, item, what=what) for item in value)
    names = [item.name for item in out]
    if len(set(names)) != len(names):
        raise ProblemError(f"{what} names must be unique, got {names}")
    return out


def _check_links(lines: tuple[KnownLine, ...], zones: tuple[KnownZone, ...]) -> None:
    """ProblemError unless every ``requires`` names an earlier line and grouped zones share a probability."""
    seen: set[str] = set()
    for line in lines:
        if line.requires and line.requires not in seen:
            raise ProblemError(
                f"known line {line.name!r} requires {line.requires!r}, which is not a line listed before it "
                f"(listed before: {sorted(seen)})"
            )
        seen.add(line.name)
    groups: dict[str, float] = {}
    for zone in zones:
        if zone.group and groups.setdefault(zone.group, zone.probability) != zone.probability:
            raise ProblemError(
                f"known zones of group {zone.group!r} must share one probability; {zone.name!r} has "
                f"{zone.probability}, the group {groups[zone.group]}"
            )


#: The default site's known power lines (lattice frame of ``trees/heli_lines_spec.json``; x points north): a
#: feeder near the start with a tap over the northern ridge, and a trunk near the goal with a tap across the
#: valley (a tap stands only where its line does).
DEFAULT_LINES: tuple[KnownLine, ...] = (
    KnownLine("west_feeder", ((450.0, -1400.0), (520.0, 0.0), (600.0, 1400.0)), 0.5),
    KnownLine("east_trunk", ((2200.0, -1400.0), (2150.0, 0.0), (2250.0, 1400.0)), 0.6),
    KnownLine("valley_tap", ((1350.0, -1400.0), (1550.0, -450.0)), 0.85, requires="east_trunk"),
    KnownLine("ridge_tap", ((1300.0, 1400.0), (1450.0, 850.0)), 0.85, requires="west_feeder"),
)

#: The default site's published no-fly zones: an airfield's airspace shelf over the valley (from 90 m above
#: the datum up), two areas of one exercise in the valley, a quarry's blasting area and a range.
DEFAULT_ZONES: tuple[KnownZone, ...] = (
    KnownZone(
        name="airfield_shelf",
        shape="prism",
        center=(1550.0, -1000.0),
        size=(1500.0, 800.0),
        z_range=(90.0, 3000.0),
        probability=0.5,
    ),
    KnownZone(name="valley_reserve", center=(1000.0, -950.0), radius=220.0, probability=0.6, group="exercise"),
    KnownZone(
        name="bridge_works",
        shape="prism",
        center=(1850.0, -1175.0),
        size=(200.0, 250.0),
        probability=0.6,
        group="exercise",
    ),
    KnownZone(
        name="quarry",
        shape="prism",
        center=(1700.0, 1150.0),
        size=(450.0, 300.0),
        yaw_deg=20.0,
        probability=0.4,
    ),
    KnownZone(name="range_west", center=(300.0, 700.0), radius=160.0, probability=0.3),
)


@dataclass(frozen=True)
class CorridorsParams(NoFlyParams):
    """Parameters of the ``"corridors"`` model (see :mod:`~drd_planner.domains.helicopter_corridors_model`).

    Attributes:
        path: the elevation grid (file), ESRI ASCII or GeoTIFF (``.tif``, ``.tiff``; its CRS must be measured
            in ``grid_units``); None: the shared SRTM Front Range grid.
        grid_units: how the grid's x and y are measured (name): "degrees" (geographic grid: x longitude,
            y latitude) or "metres" (projected grid).
        site_origin: (x, y) of the lattice origin (x = y = 0) in the grid's own coordinates (deg), or in
            metres when ``grid_units`` is "metres".
        site_heading_deg: direction of the lattice's +x axis (deg), counter-clockwise from the grid's east.
        datum: DEM height above the grid's zero, e.g. sea level (m), that is z = 0 of the world; None:
            the DEM's height at the lattice origin.
        shift_sigma: standard deviation of the DEM's horizontal registration error per axis (m); the
            world's terrain is the DEM shifted by it (drawn per world, clipped at 3 sigma; SRTM's absolute
            geolocation error is of this size).
        bias_sigma: standard deviation of the vertical offset between the DEM and the vehicle's altitude
            reference (m), drawn per world and clipped at 3 sigma: SRTM's height error (16 m at 90 %,
            more on slopes) plus the barometric altimeter's error (pressure setting and temperature).
        keep_clear_radius: radius of the pad around the start and goal where the terrain is capped below
            them (m).
        ground_gap: how far below the start/goal altitude minus the vehicle clearance the pad is capped
            (m).
        lines: the known power lines (:class:`KnownLine` records or dicts).
        zones: the published no-fly zones (:class:`KnownZone` records or dicts).
        tower_radius: radius of a tower, a vertical cylinder (m).
        tower_jitter: each tower's top differs from its line's drawn height by up to this much (m).
        conductor_gap: vertical distance between conductors (m).
        wire_diameter: conductor diameter (m).
        nofly: random no-fly zones added on top of the known ones (count), or zone dicts.
        nofly_radius: [lo, hi] radius of random cylinders (m).
        nofly_size: [lo, hi] side length of random prisms (m).
        nofly_keep_clear: how far random zones, known zones and known line routes keep from the start and
            goal, plus the vehicle clearance (m).
        nofly_region: [[x0, x1], [y0, y1]] where random zone centres are drawn (m).
        unmapped_lines: [lo, hi] power lines missing from the map (count), drawn per world: each a straight
            line across the lattice's extent through a random point at a random bearing, kept clear of the start
            and goal; its towers, heights, sag and conductors as ``unmapped_line`` says (its route and name are
            not used).
        unmapped_towers: [lo, hi] lone towers or masts missing from the map (count), drawn per world at random
            points of the lattice's extent: cylinders of ``tower_radius`` as tall as ``unmapped_line``'s
            ``tower_height``.
        unmapped_line: the template of an unmapped line (a :class:`KnownLine` record or dict).
    """

    path: str | None = None
    grid_units: str = "degrees"
    site_origin: tuple[float, float] = (-105.4617, 40.1825)
    site_heading_deg: float = 90.0
    datum: float | None = None
    shift_sigma: float = 10.0
    bias_sigma: float = 15.0
    keep_clear_radius: float = 80.0
    ground_gap: float = 10.0
    lines: tuple[KnownLine, ...] = field(default=DEFAULT_LINES)
    zones: tuple[KnownZone, ...] = field(default=DEFAULT_ZONES)
    tower_radius: float = 2.0
    tower_jitter: float = 3.0
    conductor_gap: float = 5.0
    wire_diameter: float = 0.03
    unmapped_lines: tuple[int, int] = (0, 0)
    unmapped_towers: tuple[int, int] = (0, 0)
    unmapped_line: KnownLine = field(default_factory=lambda: KnownLine("unmapped", probability=1.0))

    def __post_init__(self) -> None:
        self._check_common()
        if self.path is not None and not isinstance(self.path, str):
            raise ProblemError(f"corridors path must be a string or null, got {self.path!r}")
        if self.grid_units not in GRID_UNITS:
            raise ProblemError(f"corridors grid_units must be one of {GRID_UNITS}, got {self.grid_units!r}")
        origin = _finite_pairs([self.site_origin], "corridors site_origin", minimum=1)[0]
        object.__setattr__(self, "site_origin", origin)
        object.__setattr__(self, "site_heading_deg", _finite(self.site_heading_deg, "corridors site_heading_deg"))
        if self.datum is not None:
            object.__setattr__(self, "datum", _finite(self.datum, "corridors datum"))
        for name in ("shift_sigma", "bias_sigma", "ground_gap", "tower_jitter"):
            object.__setattr__(self, name, _positive(getattr(self, name), f"corridors {name}", zero=True))
        for name in ("keep_clear_radius", "tower_radius", "conductor_gap", "wire_diameter"):
            object.__setattr__(self, name, _positive(getattr(self, name), f"corridors {name}"))
        object.__setattr__(self, "lines", _records(self.lines, KnownLine, "corridors lines"))
        object.__setattr__(self, "zones", _records(self.zones, KnownZone, "corridors zones"))
        _check_links(self.lines, self.zones)
        for name in ("unmapped_lines", "unmapped_towers"):
            object.__setattr__(self, name, check_range(getattr(self, name), f"corridors {name}", low=0, integer=True))
        if not isinstance(self.unmapped_line, KnownLine):
            line = params_from_dict(KnownLine, self.unmapped_line, what="corridors unmapped_line")
            object.__setattr__(self, "unmapped_line", line)

    def resolved_path(self) -> Path:
        """The grid file to read (``path``, else the shared SRTM Front Range grid)."""
        return Path(self.path) if self.path else default_terrain_path()
