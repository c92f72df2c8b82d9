"""The helicopter domain: an (x, y, z, heading) Dubins lattice, seeded terrain/wire/canyon worlds, FCL checks.

Pieces (one concept per module):

- :mod:`~drd_planner.domains.helicopter_lattice`: the state lattice and every edge's sampled trajectory;
- :mod:`~drd_planner.domains.helicopter_worlds`: the world models (``"wires"``, ``"canyon"``, ``"terrain"``,
  each with optional no-fly zones) and the scene of a world;
- :mod:`~drd_planner.domains.helicopter_checker`: the sphere-sweep edge checker the node also uses.

The spec (JSON-able, see :meth:`HelicopterDomain.spec`)::

    {"lattice": {...LatticeParams...}, "vehicle_radius": 5.0, "margin": 2.0, "terrain_cell": 10.0,
     "world_margin": 100.0, "wire_segments": 8, "models": {"wires": {...}, "canyon": {...}, "terrain": {...}}}

Units: metres and radians (degrees where a name says ``_deg``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.domains.helicopter_checker import HelicopterChecker, obstacle_boxes
from drd_planner.domains.helicopter_lattice import HelicopterLattice, LatticeParams, build_lattice
from drd_planner.domains.helicopter_params import params_to_dict
from drd_planner.domains.helicopter_worlds import (
    WORLD_MODELS,
    HelicopterWorld,
    ModelParams,
    WorldFrame,
    generate_world,
    model_params_from_dict,
    world_parts,
    world_scene,
)
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.scene import Scene

__all__ = ["HelicopterDomain"]

_SPEC_KEYS = (
    "lattice",
    "vehicle_radius",
    "margin",
    "terrain_cell",
    "world_margin",
    "wire_segments",
    "models",
)


def _number(spec: Mapping[str, Any], key: str, default: float, *, low: float, strict: bool) -> float:
    value = spec.get(key, default)
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ProblemError(f"helicopter spec {key!r} must be a number, got {value!r}") from None
    ok = math.isfinite(number) and (number > low if strict else number >= low)
    if not ok:
        raise ProblemError(
            f"helicopter spec {key!r} must be finite and {'>' if strict else '>='} {low}, got {value!r}"
        )
    return number


class HelicopterDomain:
    """Helicopter planning domain (implements :class:`drd_planner.domains.base.Domain`).

    Args:
        lattice: lattice parameters (default :class:`LatticeParams`).
        vehicle_radius: vehicle sphere radius, metres (> 0, >= the lattice's sample spacing).
        margin: collision margin added to the radius, metres (>= 0).
        terrain_cell: grid spacing of generated terrain, metres.
        world_margin: how far generated terrain extends beyond the lattice corridor, metres.
        wire_segments: capsules per wire span in the scene (None: :meth:`Wire.default_segments`); the chain
            contains the wire and reaches at most ``2 sag / wire_segments**2`` metres beyond its surface
            (8 segments: 0.8 m for a 25 m sag), so fewer capsules are faster and a little conservative.
        models: per world model, its parameter record or a (partial) dict of it.

    Raises:
        ProblemError: invalid parameters.
    """

    def __init__(
        self,
        *,
        lattice: LatticeParams | None = None,
        vehicle_radius: float = 5.0,
        margin: float = 2.0,
        terrain_cell: float = 10.0,
        world_margin: float = 100.0,
        wire_segments: int | None = 8,
        models: Mapping[str, ModelParams | Mapping[str, Any]] | None = None,
    ) -> None:
        spec = {
            "vehicle_radius": vehicle_radius,
            "margin": margin,
            "terrain_cell": terrain_cell,
            "world_margin": world_margin,
        }
        self._radius = _number(spec, "vehicle_radius", 5.0, low=0.0, strict=True)
        self._margin = _number(spec, "margin", 2.0, low=0.0, strict=False)
        self._terrain_cell = _number(spec, "terrain_cell", 10.0, low=0.0, strict=True)
        self._world_margin = _number(spec, "world_margin", 100.0, low=0.0, strict=False)
        if wire_segments is not None and (
            isinstance(wire_segments, bool)
            or not isinstance(wire_segments, (int, np.integer))
            or wire_segments < 1
        ):
            raise ProblemError(
                f"helicopter spec 'wire_segments' must be an integer >= 1 or null, got {wire_segments!r}"
            )
        self._wire_segments = None if wire_segments is None else int(wire_segments)
        self._lattice = build_lattice(lattice or LatticeParams())
        params = self._lattice.params
        if params.sample_spacing > self._radius + 1e-12:
            raise ProblemError(
                f"lattice sample_spacing {params.sample_spacing} m exceeds the vehicle radius {self._radius} m; "
                "samples must be at most one radius apart"
            )
        given = dict(models or {})
        unknown = sorted(set(given) - set(WORLD_MODELS))
        if unknown:
            raise ProblemError(f"unknown helicopter world models {unknown}; known: {list(WORLD_MODELS)}")
        self._models: dict[str, ModelParams] = {}
        for name in WORLD_MODELS:
            value = given.get(name)
            if value is None or isinstance(value, Mapping):
                self._models[name] = model_params_from_dict(name, dict(value or {}))
            else:
                self._models[name] = model_params_from_dict(name, params_to_dict(value))
        states = self._lattice.graph.vertex_states
        assert states is not None
        keep = tuple(
            (float(states[i, 0]), float(states[i, 1]), float(states[i, 2])) for i in (self.start, self.goal)
        )
        self._frame = WorldFrame(
            x_range=params.x_range,
            y_range=params.y_range,
            margin=self._world_margin,
            cell_size=self._terrain_cell,
            keep_clear=keep,
            clearance=self._radius + self._margin,
            lowest_level=params.z_levels[0],
        )

    # ------------------------------------------------------------------------------------------------
    # Spec

    @classmethod
    def from_spec(cls, spec: Mapping[str, Any]) -> HelicopterDomain:
        """The domain of a (partial) spec dict; missing keys take the defaults.

        Raises:
            ProblemError: unknown keys or invalid values.
        """
        if not isinstance(spec, Mapping):
            raise ProblemError(f"helicopter spec must be a dict, got {type(spec).__name__}")
        unknown = sorted(set(spec) - set(_SPEC_KEYS))
        if unknown:
            raise ProblemError(f"unknown helicopter spec keys {unknown}; known: {list(_SPEC_KEYS)}")
        lattice = spec.get("lattice")
        if lattice is not None and not isinstance(lattice, Mapping):
            raise ProblemError(f"helicopter spec 'lattice' must be a dict, got {type(lattice).__name__}")
        models = spec.get("models")
        if models is not None and not isinstance(models, Mapping):
            raise ProblemError(f"helicopter spec 'models' must be a dict, got {type(models).__name__}")
        return cls(
            lattice=LatticeParams.from_dict(dict(lattice or {})),
            vehicle_radius=_number(spec, "vehicle_radius", 5.0, low=0.0, strict=True),
            margin=_number(spec, "margin", 2.0, low=0.0, strict=False),
            terrain_cell=_number(spec, "terrain_cell", 10.0, low=0.0, strict=True),
            world_margin=_number(spec, "world_margin", 100.0, low=0.0, strict=False),
            wire_segments=spec.get("wire_segments", 8),
            models=dict(models or {}),
        )

    def spec(self) -> dict[str, Any]:
        """The full JSON-able spec (defaults filled in); ``from_spec(spec())`` rebuilds an equal domain."""
        return {
            "lattice": self._lattice.params.to_dict(),
            "vehicle_radius": self._radius,
            "margin": self._margin,
            "terrain_cell": self._terrain_cell,
            "world_margin": self._world_margin,
            "wire_segments": self._wire_segments,
            "models": {name: params_to_dict(p) for name, p in self._models.items()},
        }

    # ------------------------------------------------------------------------------------------------
    # Domain protocol

    @property
    def name(self) -> str:
        """``"helicopter"``."""
        return "helicopter"

    @property
    def lattice(self) -> HelicopterLattice:
        """The lattice (graph, trajectories, primitives)."""
        return self._lattice

    @property
    def graph(self) -> ExplicitGraph:
        """The directed lattice graph; ``vertex_states`` (V, 4) = x, y, z (m), heading (rad)."""
        return self._lattice.graph

    @property
    def start(self) -> int:
        """Start vertex: (start x, start y, start level, heading 0)."""
        return self._lattice.start

    @property
    def goal(self) -> int:
        """Goal vertex: (goal x, goal y, goal level, heading 0)."""
        return self._lattice.goal

    @property
    def world_models(self) -> tuple[str, ...]:
        """``("wires", "canyon", "terrain")``."""
        return WORLD_MODELS

    @property
    def vehicle_radius(self) -> float:
        """Vehicle sphere radius in metres (the scene adds :attr:`margin`)."""
        return self._radius

    @property
    def margin(self) -> float:
        """Collision margin in metres."""
        return self._margin

    @property
    def frame(self) -> WorldFrame:
        """What the world models know of the lattice (corridor, terrain grid, keep-clear points)."""
        return self._frame

    def model_params(self, model: str) -> ModelParams:
        """The parameter record of world model ``model``."""
        if model not in self._models:
            raise ProblemError(
                f"unknown helicopter world model {model!r}; choose one of {', '.join(WORLD_MODELS)}"
            )
        return self._models[model]

    def make_world(self, model: str, seed: int) -> HelicopterWorld:
        """World ``seed`` of ``model`` (same arguments, same world)."""
        return generate_world(model, seed, self.model_params(model), self._frame)

    def scene(self, world: HelicopterWorld) -> Scene:
        """The collision scene of ``world`` with this domain's margin."""
        return world_scene(world, margin=self._margin, wire_segments=self._wire_segments)

    def checker(self, world: HelicopterWorld | Scene) -> HelicopterChecker:
        """The edge checker of a world (or of a ready scene, e.g. one built from ROS messages)."""
        boxes = None
        if isinstance(world, HelicopterWorld):
            parts = world_parts(world, wire_segments=self._wire_segments)
            scene = world_scene(world, margin=self._margin, parts=parts)
            boxes = obstacle_boxes([(shape, pose) for _name, shape, pose in parts])
        elif isinstance(world, Scene):
            scene = world
        else:
            raise ProblemError(
                f"helicopter checker needs a HelicopterWorld or a Scene, got {type(world).__name__}"
            )
        return HelicopterChecker(
            scene, self._lattice.points, self._lattice.offsets, radius=self._radius, boxes=boxes
        )

    def edge_trajectories(self) -> list[FloatArray]:
        """Per edge (graph order) its (K_e, 4) samples: x, y, z (m), heading (rad)."""
        return self._lattice.trajectories()

    def check_metadata(self) -> dict[str, Any]:
        """How edges are checked, with units."""
        counts = np.diff(self._lattice.offsets)
        steps = np.linalg.norm(np.diff(self._lattice.points[:, :3], axis=0), axis=1)
        inner = np.ones(steps.size, dtype=bool)
        inner[self._lattice.offsets[1:-1] - 1] = False  # steps across edge boundaries
        return {
            "method": "sphere at every trajectory sample (bisection order) vs FCL scene; centre under terrain = blocked",
            "vehicle_shape": "sphere",
            "vehicle_radius_m": self._radius,
            "margin_m": self._margin,
            "effective_radius_m": self._radius + self._margin,
            "sample_spacing_m": self._lattice.params.sample_spacing,
            "max_sample_step_m": float(steps[inner].max()) if inner.any() else 0.0,
            "samples_per_edge": {
                "min": int(counts.min()),
                "mean": float(counts.mean()),
                "max": int(counts.max()),
            },
            "terrain_cell_m": self._terrain_cell,
            "terrain_surface": "two triangles per grid cell",
            "wire_segments": self._wire_segments,
            "wire_model": "parabolic sag, capsule chain containing the wire",
        }
