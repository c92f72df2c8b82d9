"""The ``"canyon"`` helicopter world model: a plateau cut by a meandering valley, rock spurs and rim wires.

A plateau of ``wall_height`` is cut by a valley whose centre line meanders as a sine series pinned to y = 0
at both corridor ends (so start and goal lie in it); its flat floor at ``floor_height`` is ``half_width``
wide on each side, the walls rise over ``wall_width`` metres; ``spurs`` rock spurs (Gaussian bumps) narrow
it, and ``rim_wires`` wires strung rim to rim across it sag down to ``rim_wire_low``, so the helicopter must
often fly low along the floor (see :class:`~drd_planner.domains.helicopter_world_params.CanyonParams`).

Units: metres.
"""

from __future__ import annotations

import math

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.domains.helicopter_world_frame import (
    ModelDraw,
    WorldFrame,
    draw_integer,
    draw_uniform,
    smoothstep,
)
from drd_planner.domains.helicopter_world_params import CanyonParams
from drd_planner.geometry.wires import Wire

__all__ = ["draw_canyon"]


def draw_canyon(rng: np.random.Generator, p: CanyonParams, frame: WorldFrame) -> ModelDraw:
    """A plateau cut by a meandering valley, with rock spurs and rim-to-rim wires."""
    xs, ys = frame.grid()
    gx, gy = np.meshgrid(xs, ys)
    x0, x1 = frame.x_range
    amp = draw_uniform(rng, p.meander)
    coeffs = rng.normal(0.0, 1.0, size=p.meander_modes) * amp / np.arange(1, p.meander_modes + 1)

    def centre_line(x: FloatArray) -> FloatArray:
        u = (np.asarray(x) - x0) / (x1 - x0)
        y = sum(c * np.sin((i + 1) * math.pi * u) for i, c in enumerate(coeffs))
        return np.asarray(np.clip(y, -p.max_offset, p.max_offset), dtype=np.float64)

    floor = draw_uniform(rng, p.floor_height)
    wall = max(draw_uniform(rng, p.wall_height), floor + 1.0)
    half = draw_uniform(rng, p.half_width)
    slope = draw_uniform(rng, p.wall_width)
    yc = centre_line(gx)
    dist = np.abs(gy - yc)
    heights = floor + (wall - floor) * smoothstep((dist - half) / slope)
    spurs: list[dict[str, float]] = []
    for _ in range(draw_integer(rng, p.spurs)):
        sx = rng.uniform(x0 + 0.15 * (x1 - x0), x1 - 0.15 * (x1 - x0))
        side = 1.0 if rng.random() < 0.5 else -1.0
        sy = float(centre_line(np.array([sx]))[0]) + side * half * rng.uniform(0.3, 1.0)
        h, s = draw_uniform(rng, p.spur_height), draw_uniform(rng, p.spur_sigma)
        heights = heights + h * np.exp(-((gx - sx) ** 2 + (gy - sy) ** 2) / (2.0 * s * s))
        spurs.append({"x": float(sx), "y": float(sy), "height": h, "sigma": s})
    terrain = frame.heightfield(heights)
    wires: list[Wire] = []
    for _ in range(draw_integer(rng, p.rim_wires)):
        wx = rng.uniform(x0 + 0.15 * (x1 - x0), x1 - 0.15 * (x1 - x0))
        wy = float(centre_line(np.array([wx]))[0])
        reach = half + slope + 30.0
        low = min(draw_uniform(rng, p.rim_wire_low), wall - 1.0)
        skew = rng.uniform(-30.0, 30.0)
        wires.append(Wire((wx - skew, wy - reach, wall), (wx + skew, wy + reach, wall), wall - low, p.wire_diameter))
    info = {
        "meander_coefficients": coeffs.tolist(),
        "floor": floor,
        "wall": wall,
        "half_width": half,
        "wall_width": slope,
        "spurs": spurs,
    }
    return ModelDraw(terrain, tuple(wires), (), info)
