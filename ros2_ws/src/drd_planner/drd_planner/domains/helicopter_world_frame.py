"""What every helicopter world model works with: the lattice's frame, the draw it returns, the draw helpers.

A world model is a function ``draw(rng, params, frame) -> ModelDraw``: from a seeded generator, its parameter
record (:mod:`~drd_planner.domains.helicopter_world_params`) and the :class:`WorldFrame` it draws the terrain,
wires and solids; :func:`~drd_planner.domains.helicopter_worlds.generate_world` adds the no-fly zones. The
helpers here draw from ranges the way every model does, so the same seed gives the same numbers.

Units: metres.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.domains.helicopter_world_params import NoFlyZone
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Shape
from drd_planner.geometry.terrain import Heightfield
from drd_planner.geometry.wires import Wire

__all__ = ["ModelDraw", "WorldFrame", "draw_integer", "draw_uniform", "flatten_near", "smoothstep"]


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


class ModelDraw(NamedTuple):
    """What a world model draws (before the no-fly zones).

    Attributes:
        terrain: the terrain heightfield (metres).
        wires: sagging wire spans.
        solids: (name, shape, pose) solid obstacles (e.g. towers).
        info: JSON-able summary of the draw.
        nofly: no-fly zones the model itself placed (e.g. the active ones of a known list); the random
            zones of the ``nofly`` parameter come on top.
    """

    terrain: Heightfield
    wires: tuple[Wire, ...]
    solids: tuple[tuple[str, Shape, Pose], ...]
    info: dict[str, Any]
    nofly: tuple[NoFlyZone, ...] = ()


def draw_uniform(rng: np.random.Generator, r: tuple[float, float]) -> float:
    """A uniform draw from the range ``r`` = [lo, hi]; ``lo`` without drawing when the range is empty."""
    return float(rng.uniform(r[0], r[1])) if r[1] > r[0] else float(r[0])


def draw_integer(rng: np.random.Generator, r: tuple[int, int]) -> int:
    """A uniform integer from ``r`` = [lo, hi], both included."""
    return int(rng.integers(r[0], r[1] + 1))


def smoothstep(t: FloatArray) -> FloatArray:
    """The cubic smoothstep 3 t^2 - 2 t^3 of ``t`` clipped to [0, 1], elementwise."""
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def flatten_near(
    heights: FloatArray, gx: FloatArray, gy: FloatArray, keep: FloatArray, *, cap: float, radius: float
) -> FloatArray:
    """(rows, cols) ``heights`` lowered to at most ``cap`` within ``radius`` of each keep-clear point.

    ``gx``, ``gy`` are the (rows, cols) x and y of the heights and ``keep`` the (p, >= 2) keep-clear points,
    metres. The cap fades out over the next ``radius`` metres (a smoothstep), so the start and goal stay clear.
    """
    out = heights
    for point in keep:
        dist = np.hypot(gx - point[0], gy - point[1])
        weight = smoothstep((dist - radius) / radius)
        out = weight * out + (1.0 - weight) * np.minimum(out, cap)
    return np.asarray(out, dtype=np.float64)
