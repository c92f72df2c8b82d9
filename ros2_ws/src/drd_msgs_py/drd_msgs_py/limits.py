"""Size limits of map messages, checked from headers and counts before any payload is decoded.

A map message that is valid syntax can still cost more than a consumer can pay (a terrain's collision tiles
take about 1.2 KiB per cell, a 100 000-marker scene seconds to build). The converters
(:func:`drd_msgs_py.terrain.heightfield_from_cloud`, :func:`drd_msgs_py.obstacles.obstacle_update`) take a
:class:`MessageLimits` (keyword ``limits``) and refuse a message beyond one of them with an error that names the
limit, its value and the parameter that sets it::

    terrain cloud has 16000000 cells, over the limit max_terrain_cells = 250000 (parameter max_terrain_cells)

Field names are the names of the planner node's parameters (drd_planner's ``MapLimits`` extends this class
with the robot-description limits and the unknown-terrain option, and validates the values).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

__all__ = ["DEFAULT_LIMITS", "MessageLimits", "limit_refusal"]


def _doc(text: str) -> Any:
    return {"description": text}


def limit_refusal(name: str, value: object, what: str, *, side: str = "over") -> str:
    """``"<what>, over the limit <name> = <value> (parameter <name>)"`` (``side`` "under" for minimums)."""
    return f"{what}, {side} the limit {name} = {value} (parameter {name})"


@dataclass(frozen=True)
class MessageLimits:
    """Limits on the size of map messages; field names are node parameter names."""

    max_message_bytes: int = field(
        default=32 * 2**20,
        metadata=_doc(
            "bytes: largest payload of one map message (terrain cloud data, robot_description text, the strings "
            "of a MarkerArray)"
        ),
    )
    """Bytes: the largest payload of one map message (a terrain cloud's ``data``, a ``robot_description``, the
    strings of a MarkerArray's markers: ``ns``, ``frame_id``, ``text`` and ``mesh_resource`` together)."""

    max_terrain_cells: int = field(
        default=250_000,
        metadata=_doc("grid points: most rows x cols of a terrain cloud (about 1.2 KiB of memory each)"),
    )
    """Grid points: the most ``height x width`` of a terrain cloud; each costs about 1.2 KiB of FCL tiles."""

    min_terrain_cell_size: float = field(
        default=0.05,
        metadata=_doc("metres: smallest terrain grid spacing (query cost grows with (vehicle reach / cell)^2)"),
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
        metadata=_doc("points: most LINE_STRIP points (one capsule per segment) in one MarkerArray and in the map"),
    )
    """Points: the most LINE_STRIP points (one capsule per segment) in one MarkerArray and in the whole map."""

    max_mesh_triangles: int = field(
        default=100_000,
        metadata=_doc("triangles: most TRIANGLE_LIST triangles in one MarkerArray and in the map"),
    )
    """Triangles: the most TRIANGLE_LIST triangles in one MarkerArray and in the whole map."""

    def refusal(self, name: str, what: str, *, side: str = "over") -> str:
        """:func:`limit_refusal` with the value of field ``name``."""
        return limit_refusal(name, getattr(self, name), what, side=side)

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


#: The default limits (the node's parameter defaults).
DEFAULT_LIMITS = MessageLimits()
