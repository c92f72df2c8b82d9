"""The ``"wires"`` helicopter world model: rolling terrain crossed by power lines on towers.

The terrain is a sum of Gaussian bumps. Each power line passes the corridor's centre line at x ~ ``line_x``
(or, with ``line_sites``, at a random subset of those known crossings) with a heading ``line_angle_deg`` off
the y axis, has towers (vertical cylinders) every ``span`` metres of ``tower_height`` above the terrain, and
1..3 conductors ``conductor_gap`` apart hanging with a parabolic sag of ``sag`` metres (see
:class:`~drd_planner.domains.helicopter_world_params.WiresParams`).

Units: metres, degrees where the name says ``_deg``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.domains.helicopter_world_frame import ModelDraw, WorldFrame, draw_integer, draw_uniform
from drd_planner.domains.helicopter_world_params import Range, WiresParams
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Cylinder, Shape
from drd_planner.geometry.wires import Wire

__all__ = ["draw_wires"]


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
        h, s = draw_uniform(rng, height), draw_uniform(rng, sigma)
        out += h * np.exp(-((gx - cx) ** 2 + (gy - cy) ** 2) / (2.0 * s * s))
    return out


def draw_wires(rng: np.random.Generator, p: WiresParams, frame: WorldFrame) -> ModelDraw:
    """Rolling terrain crossed by power lines with towers."""
    xs, ys = frame.grid()
    gx, gy = np.meshgrid(xs, ys)
    extent = ((xs[0], xs[-1]), (ys[0], ys[-1]))
    heights = _bumps(rng, gx, gy, draw_integer(rng, p.bumps), p.bump_height, p.bump_sigma, extent)
    terrain = frame.heightfield(heights)
    wires: list[Wire] = []
    solids: list[tuple[str, Shape, Pose]] = []
    lines_info: list[dict[str, Any]] = []
    half_extent = max(abs(ys[0]), abs(ys[-1]))
    num_lines = draw_integer(rng, p.lines)
    sites: list[float] | None = None
    if p.line_sites is not None:  # known power-line corridors: which are present varies per world
        num_lines = min(num_lines, len(p.line_sites))
        picked = np.sort(rng.choice(len(p.line_sites), size=num_lines, replace=False))
        sites = [p.line_sites[int(i)] for i in picked]
    for li in range(num_lines):
        x_c = draw_uniform(rng, p.line_x) if sites is None else sites[li]
        angle = math.radians(draw_uniform(rng, p.line_angle_deg))
        span = draw_uniform(rng, p.span)
        height = draw_uniform(rng, p.tower_height)
        conductors = draw_integer(rng, p.conductors)
        direction = np.array([math.sin(angle), math.cos(angle)])
        reach = half_extent / max(math.cos(angle), 1e-6) + span
        phase = rng.uniform(0.0, span)
        ts = np.arange(-reach + phase, reach + span, span)
        bases = np.array([x_c, 0.0]) + ts[:, None] * direction
        ground = np.nan_to_num(terrain.height_at(bases), nan=0.0)
        tops = ground + height + rng.uniform(-3.0, 3.0, size=ts.size)
        sags = [draw_uniform(rng, p.sag) for _ in range(ts.size - 1)]
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
    return ModelDraw(terrain, tuple(wires), tuple(solids), {"lines": lines_info})
