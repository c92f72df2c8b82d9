"""The helicopter domain's parameters (its spec): lattice, vehicle, terrain grid, wire model, world models.

The spec (JSON-able, :meth:`HelicopterParams.to_spec`)::

    {"lattice": {...LatticeParams...}, "vehicle_radius": 5.0, "margin": 2.0, "terrain_cell": 10.0,
     "world_margin": 100.0, "wire_segments": 8, "models": {"wires": {...}, "canyon": {...}, "terrain": {...}}}

Units: metres.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from drd_planner.domains.helicopter_lattice import LatticeParams
from drd_planner.domains.helicopter_params import params_to_dict
from drd_planner.domains.helicopter_worlds import WORLD_MODELS, ModelParams, model_params_from_dict
from drd_planner.domains.params import SpecParams
from drd_planner.exceptions import ProblemError

__all__ = ["HelicopterParams"]

#: Number fields: (default, lowest value, whether the lowest value itself is refused).
_NUMBERS: dict[str, tuple[float, float, bool]] = {
    "vehicle_radius": (5.0, 0.0, True),
    "margin": (2.0, 0.0, False),
    "terrain_cell": (10.0, 0.0, True),
    "world_margin": (100.0, 0.0, False),
}


def _number(key: str, value: Any) -> float:
    """A validated number field of the spec."""
    _, low, strict = _NUMBERS[key]
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ProblemError(f"helicopter spec {key!r} must be a number, got {value!r}") from None
    if not (math.isfinite(number) and (number > low if strict else number >= low)):
        raise ProblemError(f"helicopter spec {key!r} must be finite and {'>' if strict else '>='} {low}, got {value!r}")
    return number


def _wire_segments(value: Any) -> int | None:
    if value is not None and (isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1):
        raise ProblemError(f"helicopter spec 'wire_segments' must be an integer >= 1 or null, got {value!r}")
    return None if value is None else int(value)


def _models(given: Mapping[str, Any]) -> dict[str, ModelParams]:
    """Every world model's parameter record, from records or (partial) dicts."""
    unknown = sorted(set(given) - set(WORLD_MODELS))
    if unknown:
        raise ProblemError(f"unknown helicopter world models {unknown}; known: {list(WORLD_MODELS)}")
    out: dict[str, ModelParams] = {}
    for name in WORLD_MODELS:
        value = given.get(name)
        if value is None or isinstance(value, Mapping):
            out[name] = model_params_from_dict(name, dict(value or {}))
        else:
            out[name] = model_params_from_dict(name, params_to_dict(value))
    return out


def _mapping(spec: Mapping[str, Any], key: str) -> dict[str, Any]:
    value = spec.get(key)
    if value is not None and not isinstance(value, Mapping):
        raise ProblemError(f"helicopter spec {key!r} must be a dict, got {type(value).__name__}")
    return dict(value or {})


@dataclass(frozen=True)
class HelicopterParams(SpecParams):
    """The helicopter domain's spec, validated.

    Attributes:
        lattice: lattice parameters (the ``lattice.*`` keys).
        vehicle_radius: vehicle sphere radius (m), > 0 and >= the lattice's sample spacing.
        margin: collision margin added to the radius (m), >= 0.
        terrain_cell: grid spacing of generated terrain (m), > 0.
        world_margin: how far generated terrain extends beyond the lattice corridor (m), >= 0.
        wire_segments: capsules per wire span in the scene (count); None: the wire's default.
        models: per world model its parameter record (given as records or partial dicts; every model is
            filled in).

    Raises:
        ProblemError: invalid parameters.
    """

    SPEC_LABEL: ClassVar[str] = "helicopter"

    lattice: LatticeParams = field(default_factory=LatticeParams)
    vehicle_radius: float = 5.0
    margin: float = 2.0
    terrain_cell: float = 10.0
    world_margin: float = 100.0
    wire_segments: int | None = 8
    models: Mapping[str, ModelParams | Mapping[str, Any]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for key in _NUMBERS:
            object.__setattr__(self, key, _number(key, getattr(self, key)))
        object.__setattr__(self, "wire_segments", _wire_segments(self.wire_segments))
        spacing = self.lattice.sample_spacing
        if spacing > self.vehicle_radius + 1e-12:
            raise ProblemError(
                f"lattice sample_spacing {spacing} m exceeds the vehicle radius {self.vehicle_radius} m; "
                "samples must be at most one radius apart"
            )
        object.__setattr__(self, "models", _models(dict(self.models or {})))

    @classmethod
    def from_spec(cls, spec: Mapping[str, Any]) -> HelicopterParams:
        """The parameters of a (partial) spec dict; missing keys take the defaults.

        Raises:
            ProblemError: unknown keys (the valid ones named) or invalid values.
        """
        cls.check_spec_keys(spec)
        numbers = {key: _number(key, spec.get(key, default)) for key, (default, _, _) in _NUMBERS.items()}
        return cls(
            lattice=LatticeParams.from_dict(_mapping(spec, "lattice")),
            wire_segments=spec.get("wire_segments", 8),
            models=_mapping(spec, "models"),
            **numbers,
        )

    def model(self, name: str) -> ModelParams:
        """The parameter record of world model ``name``."""
        record = self.models.get(name)
        if record is None:
            raise ProblemError(f"unknown helicopter world model {name!r}; choose one of {', '.join(WORLD_MODELS)}")
        return record  # type: ignore[return-value]

    def to_spec(self) -> dict[str, Any]:
        """The full JSON-able spec (defaults filled in); ``from_spec(to_spec())`` gives equal parameters."""
        return {
            "lattice": self.lattice.to_dict(),
            "vehicle_radius": self.vehicle_radius,
            "margin": self.margin,
            "terrain_cell": self.terrain_cell,
            "world_margin": self.world_margin,
            "wire_segments": self.wire_segments,
            "models": {name: params_to_dict(p) for name, p in self.models.items()},
        }
