"""The parameters of the helicopter lattice: grid, altitudes, turning radius, climbs and motion primitives.

See :mod:`drd_planner.domains.helicopter_lattice` for what the lattice built from them looks like. Every field
is JSON-able (through :mod:`drd_planner.domains.helicopter_params`) and validated when the record is made.

Units: metres, degrees where the name says ``_deg``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from drd_planner.domains.helicopter_params import params_from_dict, params_to_dict
from drd_planner.exceptions import ProblemError

__all__ = ["CLIMB_MODES", "LatticeParams", "Primitive"]

CLIMB_MODES: tuple[str, ...] = ("none", "straight", "all")

Primitive = tuple[int, int, int]
"""A motion primitive: (dx cells, dy cells, heading steps of 45 degrees)."""

_POSITIVE_FIELDS: tuple[str, ...] = (
    "xy_spacing",
    "turning_radius",
    "sample_spacing",
    "max_climb_gradient",
    "max_heading_deg",
)


def _positive_number(value: Any, what: str) -> float:
    """``value`` as a finite float > 0, else ProblemError."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ProblemError(f"lattice {what} must be a number, got {value!r}") from None
    if not (math.isfinite(number) and number > 0.0):
        raise ProblemError(f"lattice {what} must be positive and finite, got {value!r}")
    return number


def _number_pair(value: Any, name: str) -> tuple[float, float]:
    """``value`` as a pair of finite floats, else ProblemError."""
    try:
        a, b = (float(t) for t in value)
    except (TypeError, ValueError):
        raise ProblemError(f"lattice {name} must be a pair of numbers, got {value!r}") from None
    if not (math.isfinite(a) and math.isfinite(b)):
        raise ProblemError(f"lattice {name} must be finite, got {value!r}")
    return a, b


def _z_levels(value: Any) -> tuple[float, ...]:
    """Validated altitudes: finite, strictly increasing and (three or more) equally spaced."""
    try:
        levels = tuple(float(z) for z in value)
    except (TypeError, ValueError):
        raise ProblemError(f"lattice z_levels must be a list of numbers, got {value!r}") from None
    if not levels or not all(math.isfinite(z) for z in levels) or any(np.diff(levels) <= 0):
        raise ProblemError(f"lattice z_levels must be finite and strictly increasing, got {levels}")
    if len(levels) > 2 and np.ptp(np.diff(levels)) > 1e-6:
        raise ProblemError(f"lattice z_levels must be equally spaced, got {levels}")
    return levels


def _level(value: Any, name: str, num_levels: int) -> int:
    """A start/goal level: -1 (the middle level) or an index into ``num_levels`` levels."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not -1 <= value < num_levels:
        raise ProblemError(f"lattice {name} must be -1 (middle) or in [0, {num_levels}), got {value}")
    return int(value)


def _as_primitives(value: Any, what: str) -> tuple[Primitive, ...]:
    """Validated primitive tuples (dx cells, dy cells, heading steps of 45 degrees)."""
    try:
        prims = tuple((int(p[0]), int(p[1]), int(p[2])) for p in value)
        ok = all(len(p) == 3 for p in value)
    except (TypeError, ValueError, IndexError) as exc:
        raise ProblemError(f"{what} must be a list of [dx, dy, dheading] integer triples: {exc}") from None
    if not ok or not prims:
        raise ProblemError(f"{what} must be a non-empty list of [dx, dy, dheading] integer triples")
    if any(p[0] == 0 and p[1] == 0 for p in prims):
        raise ProblemError(f"{what}: a primitive must move ({prims})")
    if len(set(prims)) != len(prims):
        raise ProblemError(f"{what}: duplicate primitives ({prims})")
    return prims


@dataclass(frozen=True)
class LatticeParams:
    """Parameters of the helicopter lattice (all JSON-able; see :mod:`~drd_planner.domains.helicopter_lattice`).

    Attributes:
        x_range: (min, max) x of the grid (m).
        y_range: (min, max) y of the grid (m).
        xy_spacing: grid spacing in x and y (m).
        z_levels: increasing, equally spaced altitudes of the levels (m).
        turning_radius: Dubins turning radius (m).
        max_heading_deg: largest |heading| kept (deg); 180 keeps all 8 headings.
        sample_spacing: largest arc-length step between trajectory samples (m), at most ``vehicle_radius``.
        climb: which primitives get climb/descend variants (name): "none", "straight" or "all".
        max_climb_gradient: largest |dz| / horizontal length of a climbing primitive (ratio).
        start: (x, y) of the start (m); heading 0, altitude level ``start_level``.
        goal: (x, y) of the goal (m); heading 0, altitude level ``goal_level``.
        start_level: position in ``z_levels`` of the start (index); -1: the middle level.
        goal_level: position in ``z_levels`` of the goal (index); -1: the middle level.
        axis_primitives: motion primitives for heading 0 (cells): [dx cells, dy cells, heading steps of
            45 degrees] each.
        diagonal_primitives: motion primitives for heading 45 degrees (cells): [dx cells, dy cells, heading
            steps of 45 degrees] each.
    """

    x_range: tuple[float, float] = (0.0, 700.0)
    y_range: tuple[float, float] = (-250.0, 250.0)
    xy_spacing: float = 50.0
    z_levels: tuple[float, ...] = (40.0, 65.0, 90.0)
    turning_radius: float = 100.0
    max_heading_deg: float = 90.0
    sample_spacing: float = 5.0
    climb: str = "straight"
    max_climb_gradient: float = 0.5
    start: tuple[float, float] = (0.0, 0.0)
    goal: tuple[float, float] = (700.0, 0.0)
    start_level: int = -1
    goal_level: int = -1
    axis_primitives: tuple[Primitive, ...] = (
        (1, 0, 0),
        (3, 1, 0),
        (3, -1, 0),
        (2, 1, 1),
        (2, -1, -1),
        (2, 2, 2),
        (2, -2, -2),
        (3, 2, 2),
        (3, -2, -2),
    )
    diagonal_primitives: tuple[Primitive, ...] = ((1, 1, 0), (1, 2, 1), (2, 1, -1))

    def __post_init__(self) -> None:
        for name in ("x_range", "y_range", "start", "goal"):
            object.__setattr__(self, name, _number_pair(getattr(self, name), name))
        for name in ("x_range", "y_range"):
            lo, hi = getattr(self, name)
            if not lo < hi:
                raise ProblemError(f"lattice {name} must have min < max, got {(lo, hi)}")
        for name in _POSITIVE_FIELDS:
            object.__setattr__(self, name, _positive_number(getattr(self, name), name))
        levels = _z_levels(self.z_levels)
        object.__setattr__(self, "z_levels", levels)
        if self.climb not in CLIMB_MODES:
            raise ProblemError(f"lattice climb must be one of {CLIMB_MODES}, got {self.climb!r}")
        for name in ("start_level", "goal_level"):
            object.__setattr__(self, name, _level(getattr(self, name), name, len(levels)))
        object.__setattr__(self, "axis_primitives", _as_primitives(self.axis_primitives, "axis_primitives"))
        object.__setattr__(self, "diagonal_primitives", _as_primitives(self.diagonal_primitives, "diagonal_primitives"))

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict (lists for tuples) that :meth:`from_dict` turns back into equal parameters."""
        return params_to_dict(self)

    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> LatticeParams:
        """Parameters from a (partial) dict; missing keys take the defaults, unknown keys raise ProblemError."""
        return params_from_dict(cls, values, what="lattice")

    def level_index(self, which: int) -> int:
        """The level index of ``start_level``/``goal_level`` value ``which`` (-1 = middle level)."""
        return len(self.z_levels) // 2 if which < 0 else which
