"""The parameter records of the helicopter world models and their no-fly zones (frozen, validated, JSON-able).

Each world model (:mod:`~drd_planner.domains.helicopter_worlds` lists them) draws its worlds from one record:
:class:`WiresParams`, :class:`CanyonParams` or :class:`TerrainParams` (the ``"corridors"`` model's record is in
:mod:`~drd_planner.domains.helicopter_corridors_params`); ranges ``[lo, hi]`` are drawn uniformly
per world. All share the no-fly fields of :class:`NoFlyParams` (a count of random :class:`NoFlyZone` columns,
or the zones themselves). Records turn into and from dicts through :mod:`~drd_planner.domains.helicopter_params`.

Units: metres, degrees where the name says ``_deg``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner.domains.helicopter_params import check_range, params_from_dict
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Box, Cylinder, Shape
from drd_planner.settings import shared_data_dir

__all__ = [
    "DEFAULT_TERRAIN_FILE",
    "NOFLY_Z_RANGE",
    "CanyonParams",
    "NoFlyParams",
    "NoFlyZone",
    "TerrainParams",
    "WiresParams",
    "default_terrain_path",
]

#: The shared elevation model, relative to the shared data folder.
DEFAULT_TERRAIN_FILE = "terrain/srtm_front_range_144.asc"
#: Vertical extent (metres) of no-fly zones drawn at random: from below any terrain to far above the lattice.
NOFLY_Z_RANGE: tuple[float, float] = (-500.0, 3000.0)

Range = tuple[float, float]
IntRange = tuple[int, int]


def default_terrain_path() -> Path:
    """The shared elevation model: ``<shared data>/terrain/srtm_front_range_144.asc``.

    The shared data folder is ``$DRD_SHARED_DATA`` or the checkout's ``../shared/data`` (:mod:`drd_planner.settings`).
    """
    return shared_data_dir() / DEFAULT_TERRAIN_FILE


def _ranges(obj: Any, names: tuple[str, ...], *, low: float = -math.inf, integer: bool = False) -> None:
    """Validate and normalise range fields in place (frozen dataclass)."""
    for name in names:
        object.__setattr__(obj, name, check_range(getattr(obj, name), name, low=low, integer=integer))


def _positive(obj: Any, names: tuple[str, ...]) -> None:
    """Validate and normalise positive float fields in place (frozen dataclass)."""
    for name in names:
        value = getattr(obj, name)
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise ProblemError(f"{name} must be a number, got {value!r}") from None
        if not (math.isfinite(number) and number > 0.0):
            raise ProblemError(f"{name} must be finite and > 0, got {value!r}")
        object.__setattr__(obj, name, number)


def _bounded(obj: Any, name: str, low: float, high: float) -> None:
    """Validate and normalise a float field that must be finite and lie in [low, high] (frozen dataclass)."""
    value = getattr(obj, name)
    number = float(value) if isinstance(value, int | float) and not isinstance(value, bool) else math.nan
    if not (math.isfinite(number) and low <= number <= high):
        raise ProblemError(f"{name} must be a finite number in [{low:g}, {high:g}], got {value!r}")
    object.__setattr__(obj, name, number)


@dataclass(frozen=True)
class NoFlyZone:
    """A vertical no-fly column.

    Attributes:
        shape: "cylinder" or "prism" (name); a prism is a rectangular prism.
        center: (x, y) of its axis (m).
        radius: cylinder radius (m); cylinders only.
        size: (x, y) side lengths of the prism before its yaw (m); prisms only.
        yaw_deg: prism rotation about z (deg).
        z_range: (bottom, top) of the column (m).
    """

    shape: str = "cylinder"
    center: tuple[float, float] = (350.0, 0.0)
    radius: float = 50.0
    size: tuple[float, float] = (100.0, 100.0)
    yaw_deg: float = 0.0
    z_range: tuple[float, float] = NOFLY_Z_RANGE

    def __post_init__(self) -> None:
        if self.shape not in ("cylinder", "prism"):
            raise ProblemError(f"no-fly zone shape must be 'cylinder' or 'prism', got {self.shape!r}")
        try:
            cx, cy = (float(v) for v in self.center)
            sx, sy = (float(v) for v in self.size)
            yaw = float(self.yaw_deg)
        except (TypeError, ValueError):
            raise ProblemError(f"no-fly zone center/size must be pairs of numbers: {self!r}") from None
        if not all(math.isfinite(v) for v in (cx, cy, yaw)):
            raise ProblemError(f"no-fly zone center and yaw must be finite: {self!r}")
        object.__setattr__(self, "center", (cx, cy))
        object.__setattr__(self, "size", (sx, sy))
        object.__setattr__(self, "yaw_deg", yaw)
        _positive(self, ("radius",))
        if not (sx > 0 and sy > 0 and math.isfinite(sx) and math.isfinite(sy)):
            raise ProblemError(f"no-fly prism size must be finite and > 0, got {self.size}")
        z = check_range(self.z_range, "no-fly z_range")
        if z[0] >= z[1]:
            raise ProblemError(f"no-fly z_range must have bottom < top, got {z}")
        object.__setattr__(self, "z_range", z)

    @property
    def footprint_radius(self) -> float:
        """Radius of the smallest circle about ``center`` containing the footprint, metres."""
        return self.radius if self.shape == "cylinder" else 0.5 * math.hypot(*self.size)

    def solid(self) -> tuple[Shape, Pose]:
        """The zone as an FCL-ready solid shape (cylinder or box) with its world pose."""
        z0, z1 = self.z_range
        centre = (self.center[0], self.center[1], 0.5 * (z0 + z1))
        if self.shape == "cylinder":
            return Cylinder(self.radius, z1 - z0), Pose(centre)
        half = math.radians(self.yaw_deg) / 2.0
        return Box((self.size[0], self.size[1], z1 - z0)), Pose(centre, (0.0, 0.0, math.sin(half), math.cos(half)))

    def contains_xy(self, xy: npt.ArrayLike) -> npt.NDArray[np.bool_]:
        """(K,) whether each (K, 2) point lies inside the footprint (metres)."""
        p = np.asarray(xy, dtype=np.float64).reshape(-1, 2) - np.asarray(self.center)
        if self.shape == "cylinder":
            return np.asarray(np.hypot(p[:, 0], p[:, 1]) <= self.radius)
        c, s = math.cos(math.radians(self.yaw_deg)), math.sin(math.radians(self.yaw_deg))
        local_x = c * p[:, 0] + s * p[:, 1]
        local_y = -s * p[:, 0] + c * p[:, 1]
        return np.asarray((np.abs(local_x) <= self.size[0] / 2) & (np.abs(local_y) <= self.size[1] / 2))


def _nofly_value(value: Any) -> int | tuple[NoFlyZone, ...]:
    """A validated ``nofly`` parameter: a count >= 0, or zones (from dicts or NoFlyZone)."""
    if isinstance(value, bool):
        raise ProblemError(f"nofly must be a count or a list of zones, got {value!r}")
    if isinstance(value, (int, np.integer)):
        if value < 0:
            raise ProblemError(f"nofly count must be >= 0, got {value}")
        return int(value)
    if isinstance(value, (list, tuple)):
        zones: list[NoFlyZone] = []
        for item in value:
            if isinstance(item, NoFlyZone):
                zones.append(item)
            else:
                zones.append(params_from_dict(NoFlyZone, item, what="no-fly zone"))
        return tuple(zones)
    raise ProblemError(f"nofly must be a count or a list of zone dicts, got {value!r}")


@dataclass(frozen=True)
class NoFlyParams:
    """The no-fly fields every model has (metres).

    Attributes:
        nofly: how many random no-fly zones each world gets (count), or the zones themselves: a list of zone
            dicts with the keys of :class:`NoFlyZone` (shape, center, radius, size, yaw_deg, z_range).
        nofly_radius: [lo, hi] radius of random cylinders (m).
        nofly_size: [lo, hi] side length of random prisms (m).
        nofly_keep_clear: how far random zones keep from the start and goal (m), plus the vehicle clearance.
        nofly_region: [[x0, x1], [y0, y1]] where random zone centres are drawn (m).
    """

    nofly: Any = 0
    nofly_radius: Range = (25.0, 60.0)
    nofly_size: Range = (40.0, 110.0)
    nofly_keep_clear: float = 60.0
    nofly_region: tuple[Range, Range] = ((100.0, 600.0), (-250.0, 250.0))

    def _check_common(self) -> None:
        object.__setattr__(self, "nofly", _nofly_value(self.nofly))
        _ranges(self, ("nofly_radius", "nofly_size"), low=1e-9)
        _positive(self, ("nofly_keep_clear",))
        try:
            rx, ry = self.nofly_region
        except (TypeError, ValueError):
            raise ProblemError(f"nofly_region must be [[x0, x1], [y0, y1]], got {self.nofly_region!r}") from None
        object.__setattr__(self, "nofly_region", (check_range(rx, "nofly_region x"), check_range(ry, "nofly_region y")))


@dataclass(frozen=True)
class WiresParams(NoFlyParams):
    """Parameters of the ``"wires"`` model (see :mod:`~drd_planner.domains.helicopter_wires_model`).

    Ranges [lo, hi] are drawn uniformly per world (per line, per tower span where it says so).

    Attributes:
        bumps: [lo, hi] number of Gaussian bumps summed into the rolling terrain (count).
        bump_height: [lo, hi] height of each bump (m).
        bump_sigma: [lo, hi] width (standard deviation) of each bump (m).
        lines: [lo, hi] number of power lines crossing the corridor (count).
        line_x: [lo, hi] x where a line crosses the corridor's centre line (m); not used with ``line_sites``.
        line_angle_deg: [lo, hi] heading of a line off the y axis (deg).
        span: [lo, hi] distance between the towers of a line (m).
        tower_height: [lo, hi] height of a line's towers above the terrain (m).
        tower_radius: tower cylinder radius (m).
        conductors: [lo, hi] conductors per line, one above the other (count).
        conductor_gap: vertical distance between the conductors of a line (m).
        sag: [lo, hi] sag of each span at its middle, per span (m).
        wire_diameter: conductor diameter (m).
        line_sites: known x where power-line corridors cross the centre line (m); each world has ``lines`` of
            them, picked at random; null: the crossings are drawn from ``line_x``.
    """

    nofly: Any = 2
    bumps: IntRange = (3, 8)
    bump_height: Range = (5.0, 40.0)
    bump_sigma: Range = (60.0, 200.0)
    lines: IntRange = (2, 4)
    line_x: Range = (120.0, 580.0)
    line_angle_deg: Range = (-30.0, 30.0)
    span: Range = (180.0, 320.0)
    tower_height: Range = (45.0, 115.0)
    tower_radius: float = 2.0
    conductors: IntRange = (1, 3)
    conductor_gap: float = 5.0
    sag: Range = (5.0, 25.0)
    wire_diameter: float = 0.03
    line_sites: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        self._check_common()
        if self.line_sites is not None:
            sites = tuple(float(v) for v in self.line_sites)
            if not sites or not all(math.isfinite(v) for v in sites):
                raise ProblemError(f"wires line_sites must be a non-empty list of finite x, got {self.line_sites!r}")
            object.__setattr__(self, "line_sites", sites)
        _ranges(self, ("bumps", "lines", "conductors"), low=0, integer=True)
        _ranges(self, ("bump_height", "line_x", "line_angle_deg", "tower_height"))
        _ranges(self, ("bump_sigma", "span"), low=1e-9)
        _ranges(self, ("sag",), low=0.0)
        _positive(self, ("tower_radius", "conductor_gap", "wire_diameter"))


@dataclass(frozen=True)
class CanyonParams(NoFlyParams):
    """Parameters of the ``"canyon"`` model (see :mod:`~drd_planner.domains.helicopter_canyon_model`).

    Ranges [lo, hi] are drawn uniformly per world (per spur and per wire where it says so).

    Attributes:
        floor_height: [lo, hi] height of the flat valley floor (m).
        wall_height: [lo, hi] height of the plateau the valley cuts (m).
        half_width: [lo, hi] half width of the flat valley floor (m).
        wall_width: [lo, hi] horizontal distance over which the valley walls rise (m).
        meander: [lo, hi] amplitude of the meandering valley centre line (m).
        meander_modes: sine terms of the meander (count).
        max_offset: largest |y| of the valley centre line (m).
        spurs: [lo, hi] rock spurs (Gaussian bumps) narrowing the valley (count).
        spur_height: [lo, hi] height of each spur (m).
        spur_sigma: [lo, hi] width (standard deviation) of each spur (m).
        rim_wires: [lo, hi] wires strung rim to rim across the valley (count).
        rim_wire_low: [lo, hi] height a rim wire sags down to, per wire (m).
        wire_diameter: rim wire diameter (m).
    """

    floor_height: Range = (0.0, 20.0)
    wall_height: Range = (120.0, 180.0)
    half_width: Range = (70.0, 130.0)
    wall_width: Range = (40.0, 90.0)
    meander: Range = (30.0, 120.0)
    meander_modes: int = 3
    max_offset: float = 170.0
    spurs: IntRange = (0, 3)
    spur_height: Range = (30.0, 90.0)
    spur_sigma: Range = (20.0, 40.0)
    rim_wires: IntRange = (0, 2)
    rim_wire_low: Range = (50.0, 105.0)
    wire_diameter: float = 0.03

    def __post_init__(self) -> None:
        self._check_common()
        _ranges(self, ("floor_height", "wall_height", "spur_height", "rim_wire_low"))
        _ranges(self, ("half_width", "wall_width", "spur_sigma"), low=1e-9)
        _ranges(self, ("meander",), low=0.0)
        _ranges(self, ("spurs", "rim_wires"), low=0, integer=True)
        _positive(self, ("max_offset", "wire_diameter"))
        if int(self.meander_modes) != self.meander_modes or self.meander_modes < 1:
            raise ProblemError(f"meander_modes must be an integer >= 1, got {self.meander_modes!r}")
        object.__setattr__(self, "meander_modes", int(self.meander_modes))


@dataclass(frozen=True)
class TerrainParams(NoFlyParams):
    """Parameters of the ``"terrain"`` model (see :mod:`~drd_planner.domains.helicopter_terrain_model`).

    ``path`` None means :func:`default_terrain_path` (resolved when a world is drawn, not stored). Ranges
    [lo, hi] are drawn uniformly per world.

    Attributes:
        path: the ESRI ASCII elevation grid to crop (file); null: the shared Front Range grid.
        metres_per_cell: [lo, hi] metres one source grid cell spans east-west (along a row) after resampling
            (m).
        cell_aspect: how many times longer a source cell is north-south than east-west (ratio): 1 for a
            projected grid; a geographic grid's cells at latitude phi are about 1 / cos(phi) as long
            north-south (``drd build-dataset --terrain`` sets it from the site's latitude).
        relief: [lo, hi] height span of the crop's 2-98 % height range after scaling (m); null: the grid's own
            heights, not scaled (only shifted to the open fraction).
        open_fraction: [lo, hi] share of the crop lying at least the vehicle clearance below the start
            altitude (fraction).
        ground_gap: [lo, hi] how far below the start altitude the pads around start and goal are capped (m).
        keep_clear_radius: radius of the flat pads around the start and goal (m).
        max_tries: redraws of a crop window with unknown (NODATA) heights (count).
        site: [row, col] of the one operating area the crop is centred on, as fractions of the grid
            (fraction); null: a random place per world.
        site_jitter: largest shift of the crop around ``site`` per axis (m).
        rotation_deg: [lo, hi] rotation of the crop (deg).
        mirror: probability that a crop is mirrored (fraction).
    """

    path: str | None = None
    metres_per_cell: Range = (15.0, 40.0)
    cell_aspect: float = 1.0
    relief: Range | None = (80.0, 200.0)
    open_fraction: Range = (0.35, 0.85)
    ground_gap: Range = (0.0, 25.0)
    keep_clear_radius: float = 80.0
    max_tries: int = 50
    site: tuple[float, float] | None = None
    site_jitter: float = 0.0
    rotation_deg: Range = (0.0, 360.0)
    mirror: float = 0.5

    def __post_init__(self) -> None:
        self._check_common()
        if self.path is not None and not isinstance(self.path, str):
            raise ProblemError(f"terrain path must be a string or null, got {self.path!r}")
        if self.site is not None:
            try:
                row, col = (float(v) for v in self.site)
            except (TypeError, ValueError):
                raise ProblemError(f"terrain site must be [row, col] fractions or null, got {self.site!r}") from None
            if not (0.0 <= row <= 1.0 and 0.0 <= col <= 1.0):
                raise ProblemError(f"terrain site fractions must lie in [0, 1], got {self.site!r}")
            object.__setattr__(self, "site", (row, col))
        _bounded(self, "site_jitter", 0.0, math.inf)
        _bounded(self, "mirror", 0.0, 1.0)
        _ranges(self, ("rotation_deg",))
        _ranges(self, ("metres_per_cell",), low=1e-9)
        _bounded(self, "cell_aspect", 0.1, 10.0)
        if self.relief is not None:
            _ranges(self, ("relief",), low=1e-9)
        _ranges(self, ("ground_gap",))
        _ranges(self, ("open_fraction",), low=0.0)
        if self.open_fraction[1] > 1.0:
            raise ProblemError(f"open_fraction must lie in [0, 1], got {self.open_fraction}")
        _positive(self, ("keep_clear_radius",))
        if int(self.max_tries) != self.max_tries or self.max_tries < 1:
            raise ProblemError(f"max_tries must be an integer >= 1, got {self.max_tries!r}")

    def resolved_path(self) -> Path:
        """The grid file to read."""
        return Path(self.path) if self.path else default_terrain_path()
