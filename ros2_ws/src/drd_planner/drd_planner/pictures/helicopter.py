"""The helicopter's plan picture: a top view over the terrain and a side view along the plan.

The top view (x, y metres) shades the terrain heights (contour lines, a colour bar; unknown cells
blank), draws wires as dark lines and every other solid as a translucent footprint, then the edge
layers coloured by altitude (light blue low to navy high, a second colour bar in metres: edges at 40, 65
and 90 m over the same ground differ), each checked edge inside a green (free) or red (blocked) casing,
start and goal. The side view gives the altitude along the plan's horizontal distance (or the straight
start-goal line without a plan) with the vehicle radius around it, the terrain profile under it and the
heights of the wires where the plan passes over or under them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.geometry.terrain import Heightfield
from drd_planner.pictures.geometry import (
    PlanGeometry,
    along,
    end_states,
    profile_crossings,
    vehicle_radius,
)
from drd_planner.pictures.style import COLOURS, DPI, EXTRA_COLOURS, TERRAIN_CMAP, TERRAIN_CMAP_TOP
from drd_planner.pictures.view import PanelView
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.session import QuerySession
from drd_planner.planning.session_plan import SessionPlan

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.cm import ScalarMappable
    from matplotlib.figure import Figure

__all__ = [
    "ALTITUDE_CMAP",
    "ALTITUDE_CMAP_RANGE",
    "HELI_ROWS",
    "HELI_TITLE",
    "HELI_TOP_MARGIN",
    "HELI_WIDTH",
    "LIFT_MAX_PX",
    "LIFT_PX_PER_M",
    "altitude_colours",
    "edge_lift",
    "helicopter_side",
    "helicopter_top",
    "terrain_top",
]

#: The figure: width, the width beside the top view (axis labels, two colour bars), the heights of its
#: fixed rows (top view's labels, legend, side view) and of the title, inches.
HELI_WIDTH = 10.5
HELI_TOP_MARGIN = 2.9
HELI_ROWS = (0.6, 0.55, 2.7)
HELI_TITLE = 0.8
#: Edges are lifted up the top view by their altitude above the middle of the drawn range: this many
#: pixels per metre, but the whole range over at most LIFT_MAX_PX pixels.
LIFT_PX_PER_M = 0.3
LIFT_MAX_PX = 16.0
#: Colour map of edge altitudes, of which the part in :data:`ALTITUDE_CMAP_RANGE` is used: light blue
#: (low) to navy (high), apart from the outcome colours (green, red) and the terrain's light browns.
ALTITUDE_CMAP = "Blues"
ALTITUDE_CMAP_RANGE = (0.35, 1.0)


def terrain_top(fig: Figure, ax: Axes, terrain: Heightfield) -> None:
    """Shaded terrain heights with contour lines and a colour bar (metres); NaN cells stay blank."""
    from matplotlib import colormaps
    from matplotlib.colors import ListedColormap

    heights = np.ma.masked_invalid(terrain.heights)
    x0, x1, y0, y1 = terrain.extent
    h = 0.5 * terrain.cell_size
    light = ListedColormap(colormaps[TERRAIN_CMAP](np.linspace(0.0, TERRAIN_CMAP_TOP, 256)), name="terrain")
    image = ax.imshow(heights, origin="lower", extent=(x0 - h, x1 + h, y0 - h, y1 + h), cmap=light, zorder=0)
    image.set_gid("terrain")
    finite = heights.compressed()
    if finite.size and float(np.ptp(finite)) > 0.0:
        xs = x0 + terrain.cell_size * np.arange(terrain.shape[1])
        ys = y0 + terrain.cell_size * np.arange(terrain.shape[0])
        lines = ax.contour(
            xs,
            ys,
            heights,
            levels=8,
            colors=EXTRA_COLOURS["terrain_line"],
            linewidths=0.5,
            alpha=0.7,
            zorder=0.5,  # its labels go 2 above: under the footprints and edges
        )
        ax.clabel(lines, fontsize=6, fmt="%.0f m", inline=True)
    bar = fig.colorbar(image, ax=ax, shrink=0.8, pad=0.02)
    bar.set_label("terrain height (m)")


def altitude_colours(points: FloatArray) -> ScalarMappable:
    """The colour map and norm of edge altitudes over the z (metres) of (N, 3) points (at least 10 m wide)."""
    from matplotlib import colormaps
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import ListedColormap, Normalize

    z = points[:, 2] if points.shape[0] else np.zeros(1)
    lo, hi = float(np.min(z)), float(np.max(z))
    middle, half = 0.5 * (lo + hi), max(0.5 * (hi - lo), 5.0)
    shades = colormaps[ALTITUDE_CMAP](np.linspace(*ALTITUDE_CMAP_RANGE, 256))
    return ScalarMappable(norm=Normalize(middle - half, middle + half), cmap=ListedColormap(shades, "altitude"))


def edge_lift(points: FloatArray, xlim: tuple[float, float]) -> tuple[float, float]:
    """(base altitude m, metres up the picture per metre of altitude) for edges over (N, 3) points.

    The top view is about ``(HELI_WIDTH - HELI_TOP_MARGIN) * DPI`` pixels wide over ``xlim`` (m); edges
    are lifted by :data:`LIFT_PX_PER_M` pixels per metre above the middle of their altitude range, the
    whole range over at most :data:`LIFT_MAX_PX` pixels: tracks 25 m apart lie 7.5 pixels apart.
    """
    z = points[:, 2]
    lo, hi = float(np.min(z)), float(np.max(z))
    pixels_per_metre = (HELI_WIDTH - HELI_TOP_MARGIN) * DPI / max(xlim[1] - xlim[0], 1e-9)
    per_metre_px = min(LIFT_PX_PER_M, LIFT_MAX_PX / max(hi - lo, 1e-9))
    return 0.5 * (lo + hi), per_metre_px / pixels_per_metre


def helicopter_top(
    fig: Figure,
    view: PanelView,
    session: QuerySession,
    snapshot: MapSnapshot,
    result: SessionPlan,
    geometry: PlanGeometry,
) -> FloatArray:
    """The helicopter's top view; returns the wire segments."""
    if snapshot.terrain is not None:
        terrain_top(fig, view.ax, snapshot.terrain)
    start, goal = (state[:3] for state in end_states(session, result))
    points = np.vstack([geometry.points(), start, goal])
    span = float(np.max(np.ptp(points[:, :2], axis=0)))
    wires = view.draw_obstacles(snapshot, solid_label="no-fly zone / tower", min_size=0.01 * span)
    heights = altitude_colours(points)
    view.fit(points, pad=0.06)
    view.lift = edge_lift(points, view.ax.get_xlim())
    if view.record is not None:
        view.record.lift = view.lift
    view.edges(geometry, result, heights)
    view.endpoints(start, goal)
    bar = fig.colorbar(heights, ax=view.ax, shrink=0.8, pad=0.02)
    bar.set_label("edge altitude (m)")
    view.ax.set_xlabel("x (m)")
    view.ax.set_ylabel("y (m)")
    view.ax.set_title("top view: edges coloured by altitude; checked edges in a green / red casing", fontsize=10)
    return wires


def helicopter_side(
    ax: Axes,
    session: QuerySession,
    snapshot: MapSnapshot,
    result: SessionPlan,
    geometry: PlanGeometry,
    wires: FloatArray,
) -> int:
    """The side view: altitude along the plan (or along the start-goal line without one); returns the crossings."""
    start, goal = (state[:3] for state in end_states(session, result))
    planned = geometry.plan.shape[0] >= 2
    if planned:
        reference = geometry.plan
        ax.set_xlabel("horizontal distance along the plan (m)")
    else:
        steps = max(2, int(np.linalg.norm(goal[:2] - start[:2]) / 5.0) + 1)
        reference = start + np.linspace(0.0, 1.0, steps)[:, None] * (goal - start)
        ax.set_xlabel("horizontal distance along the start-goal line (m)")
    s = along(reference)
    heights = [float(reference[:, 2].min()), float(reference[:, 2].max())]
    if snapshot.terrain is not None:
        ground = snapshot.terrain.height_at(reference[:, :2])
        known = np.isfinite(ground)
        heights.extend(ground[known].tolist())
        base = min(heights) - 10.0
        ax.fill_between(
            s,
            base,
            np.where(known, ground, base),
            color=EXTRA_COLOURS["terrain_fill"],
            edgecolor=EXTRA_COLOURS["terrain_line"],
            linewidth=1.0,
            zorder=1,
            label="terrain",
        )
    if planned:
        radius = vehicle_radius(session)
        if radius > 0.0:
            z = reference[:, 2]
            band = f"vehicle radius ({radius:g} m)"
            ax.fill_between(
                s,
                z - radius,
                z + radius,
                color=COLOURS["path"],
                alpha=0.15,
                linewidth=0,
                zorder=2,
                label=band,
            )
        ax.plot(s, reference[:, 2], color=COLOURS["path"], linewidth=2.5, zorder=4, label="plan")
    else:
        direction = (goal[:2] - start[:2]) / max(float(np.linalg.norm(goal[:2] - start[:2])), 1e-9)
        for key in ("free", "blocked"):
            for k, edge in enumerate(geometry.layers[key]):
                line = geometry.polylines[edge]
                ax.plot(
                    (line[:, :2] - start[:2]) @ direction,
                    line[:, 2],
                    color=COLOURS[key],
                    linewidth=1.5,
                    zorder=4,
                    label=f"checked {key} (projected)" if k == 0 else None,
                )
                heights.extend(line[:, 2].tolist())
    cross_s, cross_z = profile_crossings(reference, wires)
    if cross_s.size:
        ax.plot(cross_s, cross_z, "X", color=EXTRA_COLOURS["wire"], markersize=8, zorder=6, label="wire crossing")
        heights.extend(cross_z.tolist())
    low, high = min(heights), max(heights)
    ax.set_xlim(float(s[0]), float(s[-1]))
    ax.set_ylim(low - 10.0, high + 0.2 * (high - low) + 10.0)
    ax.set_ylabel("altitude (m)")
    ax.set_title("side view", fontsize=10)
    ax.grid(True, linewidth=0.3, alpha=0.5)
    return int(cross_s.size)
