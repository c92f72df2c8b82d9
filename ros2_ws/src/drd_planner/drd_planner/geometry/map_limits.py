"""Limits on map messages (terrain clouds, obstacle markers, robot descriptions), checked before any allocation.

A map message that is valid syntax can still cost more than a planner can pay: a terrain's FCL tiles take about
1.2 KiB of memory per cell, a 100 000-marker scene seconds to build, a robot description with thousands of
links a quadratic self-collision table. The converters (:func:`drd_msgs_py.terrain.heightfield_from_cloud`,
:func:`drd_msgs_py.obstacles.obstacle_update`, whose message limits :class:`MapLimits` extends, and
:meth:`drd_planner.domains.arm.ArmDomain.robot_from_description`)
take a :class:`MapLimits` (keyword ``limits``) and refuse a message beyond one of them from its header or counts,
before they decode or copy its payload, with an error that names the limit, its value and the parameter::

    terrain cloud has 16000000 cells, over the limit max_terrain_cells = 250000 (parameter max_terrain_cells)

Every field name is also the name of the node parameter that sets it, so the node builds its limits with
``MapLimits.from_parameters({name: value, ...})``. The defaults keep the node's peak RSS under 1 GiB with the
largest map accepted (two terrains of :attr:`MapLimits.max_terrain_cells` alive while one replaces the other);
``scripts/experiments/bench_map_updates.py`` measures the costs.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar, cast

import numpy as np

from drd_msgs_py.limits import MessageLimits
from drd_planner.exceptions import ParameterError
from drd_planner.geometry.terrain import UNKNOWN_CHOICES, Unknown

__all__ = ["UNKNOWN_TERRAIN_CHOICES", "MapLimits", "UnknownTerrain"]

#: How unknown (NaN) terrain heights count in collision checks (see :attr:`MapLimits.unknown_terrain`).
UnknownTerrain = Unknown
#: The valid values of :attr:`MapLimits.unknown_terrain`, the safe default first.
UNKNOWN_TERRAIN_CHOICES: tuple[str, ...] = UNKNOWN_CHOICES


def _doc(text: str) -> Any:
    return {"description": text}


@dataclass(frozen=True)
class MapLimits(MessageLimits):
    """Limits on map messages and the treatment of unknown terrain; field names are node parameter names.

    The message-size fields come from :class:`drd_msgs_py.limits.MessageLimits` (the converters take a
    ``MapLimits`` as their limits); this class adds the robot-description limits and ``unknown_terrain``.
    Construction validates (:meth:`validate`): counts are positive integers, sizes finite positive floats.
    """

    max_robot_links: int = field(
        default=512,
        metadata=_doc("links: most <link> elements of a robot_description (self-collision pairs grow with links^2)"),
    )
    """Links: the most ``<link>`` elements of a robot description (self-collision pairs grow with links^2)."""

    max_robot_spheres: int = field(
        default=1024,
        metadata=_doc("spheres: most collision <sphere> elements of a robot_description (pairs grow with spheres^2)"),
    )
    """Spheres: the most collision ``<sphere>`` elements of a robot description (pairs grow with spheres^2)."""

    unknown_terrain: str = field(
        default="blocked",
        metadata=_doc(
            "unknown (NaN) terrain heights: 'blocked' (no flight over a cell with an unknown corner, at any "
            "height) or 'highest_neighbour' (an unknown region at the height of the highest known cell around it)"
        ),
    )
    """How unknown (NaN) terrain heights count: ``"blocked"`` (default: a cell with an unknown corner blocks at
    every height) or ``"highest_neighbour"`` (each unknown region takes the height of the highest known grid
    point next to it). Outside the grid there is no terrain, as before."""

    DEFAULT: ClassVar[MapLimits]

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """Check every field.

        Raises:
            ParameterError: a count that is not a positive integer, a size that is not finite and > 0, or an
                ``unknown_terrain`` that is not one of :data:`UNKNOWN_TERRAIN_CHOICES`; the text names the field.
        """
        for item in dataclasses.fields(self):
            problem = self.check_value(item.name, getattr(self, item.name))
            if problem is not None:
                raise ParameterError(f"map limit {item.name}: {problem}")

    @classmethod
    def check_value(cls, name: str, value: Any) -> str | None:
        """Why ``value`` is refused for field (parameter) ``name``, or None when it is fine.

        Raises:
            ParameterError: ``name`` is not a field of :class:`MapLimits`.
        """
        kinds = {item.name: item.type for item in dataclasses.fields(cls)}
        if name not in kinds:
            raise ParameterError(f"{name!r} is not a map limit; limits: {', '.join(kinds)}")
        if name == "unknown_terrain":
            ok = value in UNKNOWN_TERRAIN_CHOICES
            return None if ok else f"must be one of {', '.join(map(repr, UNKNOWN_TERRAIN_CHOICES))}, got {value!r}"
        if kinds[name] == "int":
            ok = bool(not isinstance(value, bool) and isinstance(value, int | np.integer) and value > 0)
            return None if ok else f"must be an integer > 0, got {value!r}"
        if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
            return f"must be a number > 0, got {value!r}"
        ok = math.isfinite(float(value)) and float(value) > 0.0
        return None if ok else f"must be finite and > 0, got {value!r}"

    @classmethod
    def from_parameters(cls, values: Mapping[str, Any]) -> MapLimits:
        """The limits with the fields named in ``values`` replaced (other keys, e.g. other node parameters, ignored).

        Integer fields accept integral floats (``4e6``); float fields accept integers.

        Raises:
            ParameterError: a value is refused (see :meth:`validate`).
        """
        names = {item.name: item.type for item in dataclasses.fields(cls)}
        given: dict[str, Any] = {}
        for name, value in values.items():
            if name not in names:
                continue
            if names[name] == "int" and isinstance(value, float) and value.is_integer():
                value = int(value)
            elif names[name] == "float" and isinstance(value, int) and not isinstance(value, bool):
                value = float(value)
            given[name] = value
        return cls(**given)

    @classmethod
    def descriptions(cls) -> dict[str, str]:
        """Field (parameter) name -> one-line description with its unit, for parameter descriptors."""
        return {item.name: str(item.metadata["description"]) for item in dataclasses.fields(cls)}

    def as_parameters(self) -> dict[str, Any]:
        """Field (parameter) name -> value."""
        return dataclasses.asdict(self)

    @property
    def unknown(self) -> UnknownTerrain:
        """:attr:`unknown_terrain` typed as :data:`UnknownTerrain`."""
        return cast(UnknownTerrain, self.unknown_terrain)


MapLimits.DEFAULT = MapLimits()
