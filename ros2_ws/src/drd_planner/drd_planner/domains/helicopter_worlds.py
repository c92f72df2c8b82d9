"""The helicopter worlds: the sampled world, the world models by name, and drawing a world from a seed.

A world is a :class:`HelicopterWorld`: a terrain :class:`Heightfield` covering the corridor plus a
margin, sagging power-line :class:`Wire` spans, solid obstacles (towers, no-fly zones) as shapes with
poses. Every model draws from a frozen parameter record (:mod:`~drd_planner.domains.helicopter_world_params`,
JSON-able through :mod:`~drd_planner.domains.helicopter_params`) inside the lattice's :class:`WorldFrame`;
``generate_world(model, seed, params, frame)`` is a pure function of its arguments (and the terrain file).

Models (:data:`WORLD_MODELS`; ranges ``[lo, hi]`` are drawn uniformly per world), each in its own module:

- ``"wires"`` (:mod:`~drd_planner.domains.helicopter_wires_model`): rolling terrain (a sum of Gaussian
  bumps) crossed by power lines on towers, 1..3 sagging conductors per line.
- ``"canyon"`` (:mod:`~drd_planner.domains.helicopter_canyon_model`): a plateau cut by a meandering valley
  that holds the start and goal, narrowed by rock spurs and crossed by rim-to-rim wires.
- ``"terrain"`` (:mod:`~drd_planner.domains.helicopter_terrain_model`): random crops, rotations and scalings
  of a real elevation model (default ``$DRD_SHARED_DATA/terrain/srtm_front_range_144.asc``), padded flat
  around the start and goal.
- ``"corridors"`` (:mod:`~drd_planner.domains.helicopter_corridors_model`): one real operating site at its
  true scale, the DEM with a random registration error, power lines on known routes (present or not,
  towers and sag uncertain) and published no-fly zones (active or not).

Every model also adds random no-fly zones (``nofly``: a count of random zones, or a list of zone dicts, see
:class:`NoFlyZone`): full-height vertical cylinders or rectangular prisms kept ``nofly_keep_clear``
metres away from the start and goal.

Units: metres, degrees where the name says ``_deg``.
"""

from __future__ import annotations

import zlib
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from drd_planner.domains.helicopter_canyon_model import draw_canyon
from drd_planner.domains.helicopter_corridors_model import CorridorsModel
from drd_planner.domains.helicopter_corridors_params import CorridorsParams
from drd_planner.domains.helicopter_params import params_from_dict
from drd_planner.domains.helicopter_terrain_model import TerrainGrids, TerrainModel
from drd_planner.domains.helicopter_wires_model import draw_wires
from drd_planner.domains.helicopter_world_frame import ModelDraw, WorldFrame, draw_uniform
from drd_planner.domains.helicopter_world_params import (
    CanyonParams,
    NoFlyZone,
    TerrainParams,
    WiresParams,
)
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Shape
from drd_planner.geometry.terrain import Heightfield
from drd_planner.geometry.wires import Wire

__all__ = [
    "WORLD_MODELS",
    "HelicopterWorld",
    "ModelParams",
    "WorldFrame",
    "generate_world",
    "model_params_from_dict",
    "world_parts",
    "world_rng",
    "world_scene",
]


ModelParams = WiresParams | CanyonParams | TerrainParams | CorridorsParams
"""The parameter record of any helicopter world model."""


class _WorldModel(NamedTuple):
    """A world model: its parameter record type and its draw ``(rng, params, frame) -> ModelDraw``."""

    params: type[WiresParams] | type[CanyonParams] | type[TerrainParams] | type[CorridorsParams]
    draw: Callable[[np.random.Generator, Any, WorldFrame], ModelDraw]


#: The elevation grids read so far (shared by the models that read grids).
_GRIDS = TerrainGrids()
#: The world models by name.
_MODELS: dict[str, _WorldModel] = {
    "wires": _WorldModel(WiresParams, draw_wires),
    "canyon": _WorldModel(CanyonParams, draw_canyon),
    "terrain": _WorldModel(TerrainParams, TerrainModel(_GRIDS).draw),
    "corridors": _WorldModel(CorridorsParams, CorridorsModel(_GRIDS).draw),
}
WORLD_MODELS: tuple[str, ...] = tuple(_MODELS)


def _world_model(model: str) -> _WorldModel:
    """The model called ``model``, or a ProblemError listing the known ones."""
    found = _MODELS.get(model)
    if found is None:
        raise ProblemError(f"unknown helicopter world model {model!r}; choose one of {', '.join(WORLD_MODELS)}")
    return found


def model_params_from_dict(model: str, values: Any) -> ModelParams:
    """The parameter record of ``model`` from a (partial) dict.

    Raises:
        ProblemError: unknown model or invalid parameters.
    """
    return params_from_dict(_world_model(model).params, values, what=f"helicopter {model!r} model")


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


def generate_world(model: str, seed: int, params: ModelParams, frame: WorldFrame) -> HelicopterWorld:
    """Draw world ``seed`` of ``model``: a pure function of its arguments (and the terrain file).

    Raises:
        ProblemError: unknown model, parameters of another model, bad seed, missing or unusable terrain file.
    """
    found = _world_model(model)
    if not isinstance(params, found.params):
        raise ProblemError(f"world model {model!r} needs {found.params.__name__}, got {type(params).__name__}")
    rng = world_rng(model, seed)
    drawn = found.draw(rng, params, frame)
    zones = drawn.nofly + _nofly_zones(rng, params, frame)
    solids = drawn.solids + tuple((f"nofly_{i}", *z.solid()) for i, z in enumerate(zones))
    return HelicopterWorld(model, int(seed), drawn.terrain, drawn.wires, solids, zones, drawn.info)


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
            zone = NoFlyZone("cylinder", centre, radius=draw_uniform(rng, p.nofly_radius))
        else:
            size = (draw_uniform(rng, p.nofly_size), draw_uniform(rng, p.nofly_size))
            zone = NoFlyZone("prism", centre, size=size, yaw_deg=float(rng.uniform(0.0, 180.0)))
        dist = np.hypot(keep[:, 0] - centre[0], keep[:, 1] - centre[1]) if keep.size else np.array([np.inf])
        if np.all(dist - zone.footprint_radius >= p.nofly_keep_clear + frame.clearance):
            zones.append(zone)
    return tuple(zones)


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
            (f"wire_{i}_{k}", shape, pose) for k, (shape, pose) in enumerate(wire.capsule_chain(wire_segments))
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
