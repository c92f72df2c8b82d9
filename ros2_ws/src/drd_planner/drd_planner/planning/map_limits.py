"""Limits on map messages (terrain clouds, obstacle markers, robot descriptions), checked before any allocation.

A map message that is valid syntax can still cost more than a planner can pay: a terrain's FCL tiles take about
1.2 KiB of memory per cell, a 100 000-marker scene seconds to build, a robot description with thousands of
links a quadratic self-collision table. The converters (:func:`drd_msgs_py.terrain.heightfield_from_cloud`,
:func:`drd_msgs_py.obstacles.obstacle_update`, :meth:`drd_planner.domains.arm.ArmDomain.robot_from_description`)
take a :class:`MapLimits` (keyword ``limits``) and refuse a message beyond one of them from its header or counts,
before they decode or copy its payload, with an error that names the limit, its value and the parameter::

    terrain cloud has 16000000 cells, over the limit max_terrain_cells = 250000 (parameter max_terrain_cells)

Every field name is also the name of the node parameter that sets it, so the node builds its limits with
``MapLimits.from_parameters({name: value, ...})``. The defaults keep the node's peak RSS under 1 GiB with the
largest map accepted (two terrains of :attr:`MapLimits.max_terrain_cells` alive while one replaces the other);
``scripts/bench_map_updates.py`` measures the costs.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar, cast

import numpy as np
import numpy.typing as npt

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
class MapLimits:
    """Limits on map messages and the treatment of unknown terrain; field names are node parameter names.

    Construction validates (:meth:`validate`): counts are positive integers, sizes finite positive floats.
    """

    max_message_bytes: int = field(
        default=32 * 2**20,
        metadata=_doc(
            "bytes: largest payload of one map message (terrain cloud data, robot_description text)"
        ),
    )
    """Bytes: the largest payload of one map message (a terrain cloud's ``data``, a ``robot_description``)."""

    max_terrain_cells: int = field(
        default=250_000,
        metadata=_doc("grid points: most rows x cols of a terrain cloud (about 1.2 KiB of memory each)"),
    )
    """Grid points: the most ``height x width`` of a terrain cloud; each costs about 1.2 KiB of FCL tiles."""

    min_terrain_cell_size: float = field(
        default=0.05,
        metadata=_doc(
            "metres: smallest terrain grid spacing (query cost grows with (vehicle reach / cell)^2)"
        ),
    )
    """Metres: the smallest terrain grid spacing; a query's cost grows with (vehicle reach / cell size)^2."""

    max_coordinate: float = field(
        default=1e6,
        metadata=_doc("metres: largest |x|, |y|, |z| of any map coordinate (terrain, robot description)"),
    )
    """Metres: the largest absolute coordinate accepted in a map (terrain points, robot joint and sphere origins)."""

    max_markers: int = field(
        default=10_000,
        metadata=_doc("obstacles: most markers in one MarkerArray and most obstacles in the obstacle map"),
    )
    """Obstacles: the most markers in one MarkerArray, and the most obstacles in the map after applying it."""

    max_line_points: int = field(
        default=100_000,
        metadata=_doc(
            "points: most LINE_STRIP points (one capsule per segment) in one MarkerArray and in the map"
        ),
    )
    """Points: the most LINE_STRIP points (one capsule per segment) in one MarkerArray and in the whole map."""

    max_mesh_triangles: int = field(
        default=100_000,
        metadata=_doc("triangles: most TRIANGLE_LIST triangles in one MarkerArray and in the map"),
    )
    """Triangles: the most TRIANGLE_LIST triangles in one MarkerArray and in the whole map."""

    max_robot_links: int = field(
        default=512,
        metadata=_doc(
            "links: most <link> elements of a robot_description (self-collision pairs grow with links^2)"
        ),
    )
    """Links: the most ``<link>`` elements of a robot description (self-collision pairs grow with links^2)."""

    max_robot_spheres: int = field(
        default=1024,
        metadata=_doc(
            "spheres: most collision <sphere> elements of a robot_description (pairs grow with spheres^2)"
        ),
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
            if value not in UNKNOWN_TERRAIN_CHOICES:
                return f"must be one of {', '.join(map(repr, UNKNOWN_TERRAIN_CHOICES))}, got {value!r}"
            return None
        if kinds[name] == "int":
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value <= 0:
                return f"must be an integer > 0, got {value!r}"
            return None
        if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
            return f"must be a number > 0, got {value!r}"
        if not (math.isfinite(float(value)) and float(value) > 0.0):
            return f"must be finite and > 0, got {value!r}"
        return None

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

    def refusal(self, name: str, what: str, *, side: str = "over") -> str:
        """``"<what>, over the limit <name> = <value> (parameter <name>)"`` (``side`` "under" for minimums)."""
        return f"{what}, {side} the limit {name} = {getattr(self, name)} (parameter {name})"

    def coordinate_problem(self, values: npt.ArrayLike, what: str) -> str | None:
        """Why ``values`` (metres, any shape; NaN allowed and skipped) are not map coordinates, or None.

        A coordinate must be finite (NaN is left to the caller) and at most :attr:`max_coordinate` in absolute value.
        """
        array = np.asarray(values, dtype=np.float64)
        if array.size == 0:
            return None
        biggest = float(np.nanmax(np.abs(array))) if not np.isnan(array).all() else 0.0
        if biggest > self.max_coordinate:
            return self.refusal("max_coordinate", f"{what} reach {biggest:.6g} m in absolute value")
        return None


MapLimits.DEFAULT = MapLimits()
