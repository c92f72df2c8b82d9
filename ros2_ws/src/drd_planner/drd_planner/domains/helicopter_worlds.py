"""Seeded generative world models of the helicopter domain: terrain, power lines, canyons, no-fly zones.

A world is a :class:`HelicopterWorld`: a terrain :class:`Heightfield` covering the corridor plus a
margin, sagging power-line :class:`Wire` spans, solid obstacles (towers, no-fly zones) as shapes with
poses. Every model is a frozen parameter record (JSON-able through
:mod:`drd_planner.domains.helicopter_params`); ``generate_world(model, seed, params, frame)`` is a pure
function of its arguments.

Models (ranges ``[lo, hi]`` are drawn uniformly per world):

- ``"wires"``: rolling terrain (a sum of Gaussian bumps) crossed by power lines. Each line passes the
  corridor's centre line at x ~ ``line_x`` (or, with ``line_sites``, at a random subset of those known
  corridor crossings, as on a map whose lines may or may not be there) with a heading ``line_angle_deg`` off
  the y axis, has towers
  (vertical cylinders) every ``span`` metres of ``tower_height`` above the terrain, and 1..3 conductors
  ``conductor_gap`` apart hanging with a parabolic sag of ``sag`` metres.
- ``"canyon"``: a plateau of ``wall_height`` cut by a valley whose centre line meanders as a sine series
  pinned to y = 0 at both corridor ends (so start and goal lie in it); its flat floor at ``floor_height``
  is ``half_width`` wide on each side, the walls rise over ``wall_width`` metres; ``spurs`` rock spurs
  (Gaussian bumps) narrow it, and ``rim_wires`` wires strung rim to rim across it sag down to
  ``rim_wire_low``, so the helicopter must often fly low along the floor.
- ``"terrain"``: the real elevation model (ESRI ASCII grid at ``path``; default
  ``$DRD_SHARED_DATA/terrain/srtm_front_range_144.asc``; any grid works, its own cell size is ignored)
  cropped at a random place, rotated by a random angle (and mirrored half the time), resampled at
  ``metres_per_cell`` metres per source cell (compressing the real ~90 m cells so a corridor holds ridges
  and valleys), scaled so its 2-98 % height range spans ``relief`` metres, and shifted so a fraction
  ``open_fraction`` of it lies at least the vehicle clearance below the start altitude. Within
  ``keep_clear_radius`` of the start and goal it is capped ``ground_gap`` below that (a smooth pad), so
  both are always clear. Windows with unknown (NODATA) heights are redrawn up to ``max_tries`` times.
  By default the crop may lie anywhere, at any rotation (``rotation_deg``), mirrored with probability
  ``mirror``; with ``site`` = [row, col] (fractions of the grid) the crop is centred on that one
  operating area, shifted by up to ``site_jitter`` metres per axis (map registration error), so all
  worlds share its ridges and valleys and only their exact position, scale and height vary.

Every model also adds no-fly zones (``nofly``: a count of random zones, or a list of zone dicts, see
:class:`NoFlyZone`): full-height vertical cylinders or rectangular prisms kept ``nofly_keep_clear``
metres away from the start and goal.

Units: metres, degrees where the name says ``_deg``.
"""

from __future__ import annotations

import math
import os
import zlib
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.domains.helicopter_params import check_range, params_from_dict, params_to_dict
from drd_planner.exceptions import GeometryError, ProblemError
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Box, Cylinder, Shape
from drd_planner.geometry.terrain import Heightfield, read_esri_ascii
from drd_planner.geometry.wires import Wire

__all__ = [
    "DEFAULT_TERRAIN_FILE",
    "WORLD_MODELS",
    "CanyonParams",
    "HelicopterWorld",
    "NoFlyZone",
    "TerrainParams",
    "WiresParams",
    "WorldFrame",
    "default_terrain_path",
    "generate_world",
    "model_params_from_dict",
    "world_parts",
    "world_scene",
]

WORLD_MODELS: tuple[str, ...] = ("wires", "canyon", "terrain")
#: The shared elevation model, relative to the shared data folder.
DEFAULT_TERRAIN_FILE = "terrain/srtm_front_range_144.asc"
#: Vertical extent (metres) of no-fly zones drawn at random: from below any terrain to far above the lattice.
NOFLY_Z_RANGE: tuple[float, float] = (-500.0, 3000.0)

Range = tuple[float, float]
IntRange = tuple[int, int]


def default_terrain_path() -> Path:
    """``$DRD_SHARED_DATA/terrain/srtm_front_range_144.asc``, or ``<repo>/../shared/data/...`` when unset."""
    env = os.environ.get("DRD_SHARED_DATA")
    if env:
        return Path(env) / DEFAULT_TERRAIN_FILE
    repo = Path(__file__).resolve().parents[5]
    return repo.parent / "shared" / "data" / DEFAULT_TERRAIN_FILE


# --------------------------------------------------------------------------------------------------
# Parameters


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
        shape: "cylinder" or "prism" (a rectangular prism).
        center: (x, y) metres of its axis.
        radius: cylinder radius, metres (cylinders only).
        size: (x, y) side lengths of the prism before its yaw, metres (prisms only).
        yaw_deg: prism rotation about z, degrees.
        z_range: (bottom, top) metres.
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
        return Box((self.size[0], self.size[1], z1 - z0)), Pose(
            centre, (0.0, 0.0, math.sin(half), math.cos(half))
        )

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
class _Common:
    """Fields every model has (no-fly zones)."""

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
            raise ProblemError(
                f"nofly_region must be [[x0, x1], [y0, y1]], got {self.nofly_region!r}"
            ) from None
        object.__setattr__(
            self, "nofly_region", (check_range(rx, "nofly_region x"), check_range(ry, "nofly_region y"))
        )


@dataclass(frozen=True)
class WiresParams(_Common):
    """Parameters of the ``"wires"`` model (see the module docstring; ranges [lo, hi], metres)."""

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
                raise ProblemError(
                    f"wires line_sites must be a non-empty list of finite x, got {self.line_sites!r}"
                )
            object.__setattr__(self, "line_sites", sites)
        _ranges(self, ("bumps", "lines", "conductors"), low=0, integer=True)
        _ranges(self, ("bump_height", "line_x", "line_angle_deg", "tower_height"))
        _ranges(self, ("bump_sigma", "span"), low=1e-9)
        _ranges(self, ("sag",), low=0.0)
        _positive(self, ("tower_radius", "conductor_gap", "wire_diameter"))


@dataclass(frozen=True)
class CanyonParams(_Common):
    """Parameters of the ``"canyon"`` model (see the module docstring; ranges [lo, hi], metres)."""

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
class TerrainParams(_Common):
    """Parameters of the ``"terrain"`` model (see the module docstring; ranges [lo, hi], metres).

    ``path`` None means :func:`default_terrain_path` (resolved when a world is drawn, not stored).
    """

    path: str | None = None
    metres_per_cell: Range = (15.0, 40.0)
    relief: Range = (80.0, 200.0)
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
                raise ProblemError(
                    f"terrain site must be [row, col] fractions or null, got {self.site!r}"
                ) from None
            if not (0.0 <= row <= 1.0 and 0.0 <= col <= 1.0):
                raise ProblemError(f"terrain site fractions must lie in [0, 1], got {self.site!r}")
            object.__setattr__(self, "site", (row, col))
        _bounded(self, "site_jitter", 0.0, math.inf)
        _bounded(self, "mirror", 0.0, 1.0)
        _ranges(self, ("rotation_deg",))
        _ranges(self, ("metres_per_cell", "relief"), low=1e-9)
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


ModelParams = WiresParams | CanyonParams | TerrainParams
_PARAM_CLASSES: dict[str, type[WiresParams] | type[CanyonParams] | type[TerrainParams]] = {
    "wires": WiresParams,
    "canyon": CanyonParams,
    "terrain": TerrainParams,
}


def model_params_from_dict(model: str, values: Any) -> ModelParams:
    """The parameter record of ``model`` from a (partial) dict.

    Raises:
        ProblemError: unknown model or invalid parameters.
    """
    cls = _PARAM_CLASSES.get(model)
    if cls is None:
        raise ProblemError(
            f"unknown helicopter world model {model!r}; choose one of {', '.join(WORLD_MODELS)}"
        )
    return params_from_dict(cls, values, what=f"helicopter {model!r} model")


# --------------------------------------------------------------------------------------------------
# Worlds


@dataclass(frozen=True)
class WorldFrame:
    """What a world model needs to know about the lattice.

    Attributes:
        x_range: (min, max) x of the corridor, metres.
        y_range: (min, max) y of the corridor, metres.
        margin: how far the terrain extends beyond the corridor on every side, metres.
        cell_size: terrain grid spacing, metres.
        keep_clear: (p, 3) points (start and goal positions) that obstacles keep away from, metres.
        clearance: vehicle radius plus collision margin, metres.
        lowest_level: the lowest lattice altitude, metres.
    """

    x_range: tuple[float, float]
    y_range: tuple[float, float]
    margin: float
    cell_size: float
    keep_clear: tuple[tuple[float, float, float], ...]
    clearance: float
    lowest_level: float

    def grid(self) -> tuple[FloatArray, FloatArray]:
        """(cols,) x and (rows,) y coordinates of the terrain grid points, metres."""
        xs = np.arange(self.x_range[0] - self.margin, self.x_range[1] + self.margin + 1e-9, self.cell_size)
        ys = np.arange(self.y_range[0] - self.margin, self.y_range[1] + self.margin + 1e-9, self.cell_size)
        return xs, ys

    def heightfield(self, heights: FloatArray) -> Heightfield:
        """A heightfield of (rows, cols) ``heights`` on :meth:`grid`."""
        xs, ys = self.grid()
        return Heightfield((xs[0], ys[0]), self.cell_size, heights)


@dataclass(frozen=True)
class HelicopterWorld:
    """One sampled world.

    Attributes:
        model: the world model's name.
        seed: the seed it was drawn with.
        terrain: the terrain heightfield (metres).
        wires: sagging wire spans.
        solids: (name, shape, pose) solid obstacles: towers and no-fly zones.
        nofly: the no-fly zones (also among ``solids``).
        info: JSON-able summary of the draw (e.g. the valley centre line, the crop).
    """

    model: str
    seed: int
    terrain: Heightfield
    wires: tuple[Wire, ...] = ()
    solids: tuple[tuple[str, Shape, Pose], ...] = ()
    nofly: tuple[NoFlyZone, ...] = ()
    info: dict[str, Any] = field(default_factory=dict)


_SALT = {name: zlib.crc32(name.encode()) for name in WORLD_MODELS}


def world_rng(model: str, seed: int) -> np.random.Generator:
    """The generator of world ``(model, seed)``: independent streams per model, same seed same stream."""
    if int(seed) != seed or seed < 0:
        raise ProblemError(f"world seed must be an integer >= 0, got {seed!r}")
    return np.random.default_rng(np.random.SeedSequence([int(seed), _SALT[model]]))


def _uniform(rng: np.random.Generator, r: tuple[float, float]) -> float:
    return float(rng.uniform(r[0], r[1])) if r[1] > r[0] else float(r[0])


def _integer(rng: np.random.Generator, r: tuple[int, int]) -> int:
    return int(rng.integers(r[0], r[1] + 1))


def generate_world(model: str, seed: int, params: ModelParams, frame: WorldFrame) -> HelicopterWorld:
    """Draw world ``seed`` of ``model``: a pure function of its arguments (and the terrain file).

    Raises:
        ProblemError: unknown model, parameters of another model, bad seed, missing or unusable terrain file.
    """
    if model not in _PARAM_CLASSES:
        raise ProblemError(
            f"unknown helicopter world model {model!r}; choose one of {', '.join(WORLD_MODELS)}"
        )
    if not isinstance(params, _PARAM_CLASSES[model]):
        raise ProblemError(
            f"world model {model!r} needs {_PARAM_CLASSES[model].__name__}, got {type(params).__name__}"
        )
    rng = world_rng(model, seed)
    if isinstance(params, WiresParams):
        world = _wires_world(rng, params, frame)
    elif isinstance(params, CanyonParams):
        world = _canyon_world(rng, params, frame)
    else:
        world = _terrain_world(rng, params, frame)
    terrain, wires, solids, info = world
    zones = _nofly_zones(rng, params, frame)
    solids = solids + tuple((f"nofly_{i}", *z.solid()) for i, z in enumerate(zones))
    return HelicopterWorld(model, int(seed), terrain, wires, solids, zones, info)


World = tuple[Heightfield, tuple[Wire, ...], tuple[tuple[str, Shape, Pose], ...], dict[str, Any]]


def _bumps(
    rng: np.random.Generator,
    gx: FloatArray,
    gy: FloatArray,
    count: int,
    height: Range,
    sigma: Range,
    extent: Any,
) -> FloatArray:
    """Sum of ``count`` Gaussian bumps on the (rows, cols) grid ``gx``, ``gy`` (metres)."""
    out = np.zeros_like(gx)
    (x0, x1), (y0, y1) = extent
    for _ in range(count):
        cx, cy = rng.uniform(x0, x1), rng.uniform(y0, y1)
        h, s = _uniform(rng, height), _uniform(rng, sigma)
        out += h * np.exp(-((gx - cx) ** 2 + (gy - cy) ** 2) / (2.0 * s * s))
    return out


def _wires_world(rng: np.random.Generator, p: WiresParams, frame: WorldFrame) -> World:
    """Rolling terrain crossed by power lines with towers."""
    xs, ys = frame.grid()
    gx, gy = np.meshgrid(xs, ys)
    extent = ((xs[0], xs[-1]), (ys[0], ys[-1]))
    heights = _bumps(rng, gx, gy, _integer(rng, p.bumps), p.bump_height, p.bump_sigma, extent)
    terrain = frame.heightfield(heights)
    wires: list[Wire] = []
    solids: list[tuple[str, Shape, Pose]] = []
    lines_info: list[dict[str, Any]] = []
    half_extent = max(abs(ys[0]), abs(ys[-1]))
    num_lines = _integer(rng, p.lines)
    sites: list[float] | None = None
    if p.line_sites is not None:  # known power-line corridors: which are present varies per world
        num_lines = min(num_lines, len(p.line_sites))
        picked = np.sort(rng.choice(len(p.line_sites), size=num_lines, replace=False))
        sites = [p.line_sites[int(i)] for i in picked]
    for li in range(num_lines):
        x_c = _uniform(rng, p.line_x) if sites is None else sites[li]
        angle = math.radians(_uniform(rng, p.line_angle_deg))
        span = _uniform(rng, p.span)
        height = _uniform(rng, p.tower_height)
        conductors = _integer(rng, p.conductors)
        direction = np.array([math.sin(angle), math.cos(angle)])
        reach = half_extent / max(math.cos(angle), 1e-6) + span
        phase = rng.uniform(0.0, span)
        ts = np.arange(-reach + phase, reach + span, span)
        bases = np.array([x_c, 0.0]) + ts[:, None] * direction
        ground = np.nan_to_num(terrain.height_at(bases), nan=0.0)
        tops = ground + height + rng.uniform(-3.0, 3.0, size=ts.size)
        sags = [_uniform(rng, p.sag) for _ in range(ts.size - 1)]
        for k in range(ts.size):
            length = tops[k] - ground[k] + 10.0
            centre = (bases[k, 0], bases[k, 1], ground[k] - 10.0 + length / 2.0)
            solids.append((f"tower_{li}_{k}", Cylinder(p.tower_radius, length), Pose(centre)))
        for k in range(ts.size - 1):
            for c in range(conductors):
                dz = c * p.conductor_gap
                a = (bases[k, 0], bases[k, 1], tops[k] - dz)
                b = (bases[k + 1, 0], bases[k + 1, 1], tops[k + 1] - dz)
                wires.append(Wire(a, b, sags[k], p.wire_diameter))
        lines_info.append(
            {
                "x": x_c,
                "angle_deg": math.degrees(angle),
                "span": span,
                "tower_height": height,
                "conductors": conductors,
            }
        )
    return terrain, tuple(wires), tuple(solids), {"lines": lines_info}


def _smoothstep(t: FloatArray) -> FloatArray:
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def _canyon_world(rng: np.random.Generator, p: CanyonParams, frame: WorldFrame) -> World:
    """A plateau cut by a meandering valley, with rock spurs and rim-to-rim wires."""
    xs, ys = frame.grid()
    gx, gy = np.meshgrid(xs, ys)
    x0, x1 = frame.x_range
    amp = _uniform(rng, p.meander)
    coeffs = rng.normal(0.0, 1.0, size=p.meander_modes) * amp / np.arange(1, p.meander_modes + 1)

    def centre_line(x: FloatArray) -> FloatArray:
        u = (np.asarray(x) - x0) / (x1 - x0)
        y = sum(c * np.sin((i + 1) * math.pi * u) for i, c in enumerate(coeffs))
        return np.asarray(np.clip(y, -p.max_offset, p.max_offset), dtype=np.float64)

    floor = _uniform(rng, p.floor_height)
    wall = max(_uniform(rng, p.wall_height), floor + 1.0)
    half = _uniform(rng, p.half_width)
    slope = _uniform(rng, p.wall_width)
    yc = centre_line(gx)
    dist = np.abs(gy - yc)
    heights = floor + (wall - floor) * _smoothstep((dist - half) / slope)
    spurs: list[dict[str, float]] = []
    for _ in range(_integer(rng, p.spurs)):
        sx = rng.uniform(x0 + 0.15 * (x1 - x0), x1 - 0.15 * (x1 - x0))
        side = 1.0 if rng.random() < 0.5 else -1.0
        sy = float(centre_line(np.array([sx]))[0]) + side * half * rng.uniform(0.3, 1.0)
        h, s = _uniform(rng, p.spur_height), _uniform(rng, p.spur_sigma)
        heights = heights + h * np.exp(-((gx - sx) ** 2 + (gy - sy) ** 2) / (2.0 * s * s))
        spurs.append({"x": float(sx), "y": float(sy), "height": h, "sigma": s})
    terrain = frame.heightfield(heights)
    wires: list[Wire] = []
    for _ in range(_integer(rng, p.rim_wires)):
        wx = rng.uniform(x0 + 0.15 * (x1 - x0), x1 - 0.15 * (x1 - x0))
        wy = float(centre_line(np.array([wx]))[0])
        reach = half + slope + 30.0
        low = min(_uniform(rng, p.rim_wire_low), wall - 1.0)
        skew = rng.uniform(-30.0, 30.0)
        wires.append(
            Wire((wx - skew, wy - reach, wall), (wx + skew, wy + reach, wall), wall - low, p.wire_diameter)
        )
    info = {
        "meander_coefficients": coeffs.tolist(),
        "floor": floor,
        "wall": wall,
        "half_width": half,
        "wall_width": slope,
        "spurs": spurs,
    }
    return terrain, tuple(wires), (), info


@lru_cache(maxsize=4)
def _load_grid(path: str, mtime_ns: int) -> Heightfield:
    """The grid at ``path`` (cached per file version)."""
    del mtime_ns  # part of the cache key only
    return read_esri_ascii(path)


def load_terrain_grid(path: Path) -> Heightfield:
    """Read an ESRI ASCII grid (cached), raising ProblemError with the path when it is missing or bad."""
    if not path.is_file():
        raise ProblemError(
            f"terrain elevation grid {path} not found; set the terrain model's 'path' or DRD_SHARED_DATA "
            f"(expected {DEFAULT_TERRAIN_FILE} under it)"
        )
    try:
        return _load_grid(str(path.resolve()), path.stat().st_mtime_ns)
    except GeometryError as exc:
        raise ProblemError(f"cannot use terrain grid {path}: {exc}") from exc


def _bilinear_index(grid: FloatArray, fi: FloatArray, fj: FloatArray) -> FloatArray:
    """Bilinear samples of (rows, cols) ``grid`` at fractional (row, col) indices (inside the grid)."""
    rows, cols = grid.shape
    i = np.clip(np.floor(fi).astype(np.int64), 0, rows - 2)
    j = np.clip(np.floor(fj).astype(np.int64), 0, cols - 2)
    v, u = fi - i, fj - j
    return np.asarray(
        (1 - v) * ((1 - u) * grid[i, j] + u * grid[i, j + 1])
        + v * ((1 - u) * grid[i + 1, j] + u * grid[i + 1, j + 1])
    )


def _flatten_near(
    heights: FloatArray, gx: FloatArray, gy: FloatArray, keep: FloatArray, *, cap: float, radius: float
) -> FloatArray:
    """``heights`` lowered to at most ``cap`` within ``radius`` of each keep-clear point.

    The cap fades out over the next ``radius`` metres (a smoothstep), so the start and goal are always clear.
    """
    out = heights
    for point in keep:
        dist = np.hypot(gx - point[0], gy - point[1])
        weight = _smoothstep((dist - radius) / radius)
        out = weight * out + (1.0 - weight) * np.minimum(out, cap)
    return np.asarray(out, dtype=np.float64)


def _terrain_world(rng: np.random.Generator, p: TerrainParams, frame: WorldFrame) -> World:
    """A random crop, rotation, resampling and vertical scaling of the real elevation model."""
    path = p.resolved_path()
    source = load_terrain_grid(path)
    grid = source.heights
    rows, cols = grid.shape
    xs, ys = frame.grid()
    gx, gy = np.meshgrid(xs, ys)
    cx, cy = 0.5 * (xs[0] + xs[-1]), 0.5 * (ys[0] + ys[-1])
    half_diag = 0.5 * math.hypot(xs[-1] - xs[0], ys[-1] - ys[0])
    keep = np.asarray(frame.keep_clear, dtype=np.float64).reshape(-1, 3)
    for _attempt in range(p.max_tries):
        mpc = _uniform(rng, p.metres_per_cell)
        radius_cells = half_diag / mpc
        if 2.0 * radius_cells > min(rows, cols) - 1:
            continue
        if p.site is None:
            ci = rng.uniform(radius_cells, rows - 1 - radius_cells)
            cj = rng.uniform(radius_cells, cols - 1 - radius_cells)
        else:
            jitter_cells = p.site_jitter / mpc
            ci = p.site[0] * (rows - 1) + rng.uniform(-jitter_cells, jitter_cells)
            cj = p.site[1] * (cols - 1) + rng.uniform(-jitter_cells, jitter_cells)
            if not (
                radius_cells <= ci <= rows - 1 - radius_cells
                and radius_cells <= cj <= cols - 1 - radius_cells
            ):
                continue
        theta = math.radians(_uniform(rng, p.rotation_deg))
        flip = bool(rng.random() < p.mirror)
        dx, dy = (gx - cx) / mpc, (gy - cy) / mpc
        if flip:
            dx = -dx
        c, s = math.cos(theta), math.sin(theta)
        heights = _bilinear_index(grid, ci + s * dx + c * dy, cj + c * dx - s * dy)
        if np.isnan(heights).any():
            continue
        lo, hi = np.percentile(heights, [2.0, 98.0])
        relief = _uniform(rng, p.relief)
        heights = (heights - lo) * (relief / max(float(hi - lo), 1.0))
        target = (float(keep[:, 2].min()) if keep.size else frame.lowest_level) - frame.clearance
        open_fraction = _uniform(rng, p.open_fraction)
        shift = target - float(np.quantile(heights, open_fraction))
        heights = heights + shift
        gap = _uniform(rng, p.ground_gap)
        heights = _flatten_near(heights, gx, gy, keep, cap=target - gap, radius=p.keep_clear_radius)
        info = {
            "path": str(path),
            "metres_per_cell": mpc,
            "centre_cell": [ci, cj],
            "rotation_deg": math.degrees(theta),
            "flipped": flip,
            "relief": relief,
            "open_fraction": open_fraction,
            "ground_gap": gap,
            "shift": shift,
        }
        return frame.heightfield(heights), (), (), info
    raise ProblemError(
        f"terrain grid {path} ({rows} x {cols} cells) has no NaN-free window for a {2 * half_diag:.0f} m corridor "
        f"at {p.metres_per_cell} m per cell after {p.max_tries} tries; lower metres_per_cell"
        + ("" if p.site is None else " or move the site away from the grid's border")
    )


def _nofly_zones(rng: np.random.Generator, p: ModelParams, frame: WorldFrame) -> tuple[NoFlyZone, ...]:
    """The model's no-fly zones: given ones, or ``nofly`` random zones away from the keep-clear points."""
    if not isinstance(p.nofly, int):
        return tuple(p.nofly)
    keep = np.asarray(frame.keep_clear, dtype=np.float64).reshape(-1, 3)[:, :2]
    zones: list[NoFlyZone] = []
    (rx0, rx1), (ry0, ry1) = p.nofly_region
    tries = 0
    while len(zones) < p.nofly and tries < 1000 * max(p.nofly, 1):
        tries += 1
        centre = (float(rng.uniform(rx0, rx1)), float(rng.uniform(ry0, ry1)))
        if rng.random() < 0.5:
            zone = NoFlyZone("cylinder", centre, radius=_uniform(rng, p.nofly_radius))
        else:
            size = (_uniform(rng, p.nofly_size), _uniform(rng, p.nofly_size))
            zone = NoFlyZone("prism", centre, size=size, yaw_deg=float(rng.uniform(0.0, 180.0)))
        dist = np.hypot(keep[:, 0] - centre[0], keep[:, 1] - centre[1]) if keep.size else np.array([np.inf])
        if np.all(dist - zone.footprint_radius >= p.nofly_keep_clear + frame.clearance):
            zones.append(zone)
    return tuple(zones)


def params_dict(params: ModelParams) -> dict[str, Any]:
    """JSON-able dict of a model's parameters (no-fly zones as dicts)."""
    return params_to_dict(params)


def world_parts(world: HelicopterWorld, *, wire_segments: int | None = None) -> list[tuple[str, Shape, Pose]]:
    """Every non-terrain collision part of a world, named: wire capsules (``wire_<i>_<k>``), then solids.

    Args:
        world: the world.
        wire_segments: capsules per wire span (None: :meth:`Wire.default_segments`, exact to the wire radius);
            fewer capsules are faster; the chain reaches at most ``2 sag / segments**2`` metres beyond the wire.
    """
    parts: list[tuple[str, Shape, Pose]] = []
    for i, wire in enumerate(world.wires):
        parts.extend(
            (f"wire_{i}_{k}", shape, pose)
            for k, (shape, pose) in enumerate(wire.capsule_chain(wire_segments))
        )
    parts.extend(world.solids)
    return parts


def world_scene(
    world: HelicopterWorld,
    *,
    margin: float,
    wire_segments: int | None = None,
    parts: list[tuple[str, Shape, Pose]] | None = None,
) -> Scene:
    """The collision scene of a world: its terrain and :func:`world_parts` (or the given ``parts``).

    Args:
        world: the world.
        margin: the scene's safety margin, metres.
        wire_segments: see :func:`world_parts`.
        parts: precomputed ``world_parts(world, wire_segments=...)``.
    """
    scene = Scene(margin=margin)
    scene.add_terrain(world.terrain)
    for name, shape, pose in world_parts(world, wire_segments=wire_segments) if parts is None else parts:
        scene.add(shape, pose, name=name)
    return scene
