"""A picture of one plan: the maps, the library, every check (green free, red blocked) and the plan.

:func:`plan_picture` writes it (PNG and/or SVG); :func:`draw_plan_picture` returns the figure with what
it drew, so tests can compare the picture with its data. Its title says what was planned and how it
ended, what served it (:func:`served_by`: the precomputed tree, a library and tree built online, or
"served from cache" when every check came from the map's check cache or the query's library and tree
were reused), and how many checks were free and blocked. Two panels:

- **helicopter** (x, y, z metres first in the states; :mod:`~drd_planner.pictures.helicopter`):
  a *top view* with the terrain heights (shaded, with contour lines and a colour bar; unknown cells
  blank), wires (obstacles made only of capsules) as dark lines, every other solid (no-fly zones,
  towers: boxes, cylinders, spheres, meshes) as a translucent footprint, the edges coloured by their
  altitude (a second colour bar in metres), each checked edge inside a green (free) or red (blocked)
  casing with its check number (1 = first), the plan as a wide blue band, start and goal; one legend
  for both views in a row of its own; and a *side view*: altitude along the plan's horizontal distance
  with the vehicle radius around it, the terrain profile under it and the heights of the wires where the
  plan passes over or under them. Without a plan the side view runs along the straight start-goal line
  and shows the checked edges projected onto it. The figure's height follows the top view's aspect.
- **arm** (``session.domain.name == "arm"``; :mod:`~drd_planner.pictures.arm`): the
  end-effector paths (:meth:`QuerySession.positions` of each edge's joint samples, the positions the
  node publishes) in a top view (x, y) and a side view (the vertical plane through the start-goal
  direction of the end effector), with the obstacles' outlines projected onto each plane and the arm (its
  joint frames) drawn at its start and goal; checked edges green / red with their numbers.

Check numbers never hide an obstacle: once the layout is fixed, each is put on its edge or, where that
would cover a wire, tower or footprint, beside it with a leader line
(:mod:`~drd_planner.pictures.labels`); obstacle lines are drawn above the numbers, and the
legend sits outside the views. What is drawn is computed in world coordinates (numpy only) by
:mod:`~drd_planner.pictures.geometry`; the drawing pieces every view shares are in
:mod:`~drd_planner.pictures.view`.

matplotlib is the optional ``plots`` extra: it is imported when a picture is drawn, through its Agg
canvas only (no pyplot, nothing global), and a missing install raises :class:`PictureError`. The
same inputs give the same bytes (no dates or software tags, fixed SVG ids).
"""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import Any

from drd_planner.pictures.arm import arm_views
from drd_planner.pictures.geometry import TOP, PictureError, PlanGeometry
from drd_planner.pictures.helicopter import (
    HELI_ROWS,
    HELI_TITLE,
    HELI_TOP_MARGIN,
    HELI_WIDTH,
    helicopter_side,
    helicopter_top,
)
from drd_planner.pictures.style import DPI
from drd_planner.pictures.view import PanelView, PlanDrawing, legend_entries, require_matplotlib
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.session import QuerySession
from drd_planner.planning.session_plan import SessionPlan

__all__ = ["DPI", "PictureError", "PlanDrawing", "draw_plan_picture", "plan_picture", "served_by"]

#: Longest title line before it wraps, in characters per inch of figure width (11 pt text).
TITLE_CHARS_PER_INCH = 11.0


def served_by(result: SessionPlan, *, query_cached: bool = False) -> str:
    """One line on what served a plan; it starts "served from cache" when no new work was needed.

    A plan is served from cache when every one of its checks was answered from the map snapshot's
    check cache (a repeated request on the same maps: no new collision check), or when the library and
    tree of a new query were reused from the planner's query cache (built online by an earlier request).

    Args:
        result: the plan; it names its query (``tree:<name>``, ``online``, ``connected``; "" when refused).
        query_cached: the query's library and tree came from the planner's query cache (the caller
            knows; only meaningful for ``online`` and ``connected`` queries).
    """
    query = result.query
    online = query in ("online", "connected")
    if query.startswith("tree:"):
        source = f"the precomputed DiRECt tree {query[5:]!r}"
    elif online and result.stage == "probe":
        source = "the probe (the union path checked first; no library built)"
    elif online and result.stage == "lead":
        source = "the lead (a lazy search within the library's cost in checks; no library built)"
    elif online and query_cached:
        source = "the library and DiRECt tree built online for this query earlier"
    elif online:
        source = "a library and DiRECt tree built online for this query"
    else:
        source = "no library (refused before planning)"
    if query == "connected":
        source += " (joined by new motions)"
    total = len(result.checks)
    cached = sum(c.cached for c in result.checks)
    if total and cached == total:
        where = f"map v{result.map_version}'s check cache"
        return f"served from cache: all {total} checks answered from {where}; {source}"
    reused = f"; {cached} of {total} checks from the map's check cache" if cached else ""
    if online and query_cached:
        return f"served from cache: {source}{reused}"
    return f"served by {source}{reused}"


def _title(session: QuerySession, result: SessionPlan, title: str | None) -> str:
    """The figure title: the given one, else tree, map version, outcome (the reason when there is no plan)."""
    if title is not None:
        return title
    head = f"{session.name} (map v{result.map_version})"
    return f"{head}: {result.message}" if result.ok else f"{head}: NO PLAN - {result.message}"


def draw_plan_picture(
    session: QuerySession,
    snapshot: MapSnapshot,
    result: SessionPlan,
    *,
    title: str | None = None,
    query_cached: bool = False,
) -> PlanDrawing:
    """Draw one plan (or a failed request) on a new figure; see the module docstring.

    Args:
        session: the session that planned (its domain, library and edge geometry).
        snapshot: the maps it planned on.
        result: its result (checks in order; path edges and states when ok).
        title: first title line (default: tree, map version, outcome or why there is no plan); the
            second says what served the plan (:func:`served_by`), the third counts the checks.
        query_cached: the query's library and tree were reused from the planner's query cache (see
            :func:`served_by`).

    Raises:
        PictureError: matplotlib is not installed.
    """
    require_matplotlib()
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    geometry = PlanGeometry(session, snapshot, result)
    if session.domain.name == "arm":
        fig = Figure(figsize=(13.0, 6.4), dpi=DPI, layout="constrained")
        top, side = fig.subplots(1, 2)
        drawing = PlanDrawing(fig, top, side)
        arm_views(top, side, session, snapshot, result, geometry, drawing)
    else:
        drawing = _helicopter_picture(session, snapshot, result, geometry)
        fig = drawing.figure
    FigureCanvasAgg(fig)
    free = len(result.checks) - result.num_blocked
    summary = (
        f"{len(result.checks)} checks: {free} free (green), {result.num_blocked} blocked (red); "
        "numbers give the check order"
    )
    lines = [_title(session, result, title), served_by(result, query_cached=query_cached), summary]
    width = int(TITLE_CHARS_PER_INCH * fig.get_figwidth())
    fig.suptitle("\n".join(textwrap.fill(line, width) for line in lines), fontsize=11)
    fig.draw_without_rendering()  # fixes the layout: the numbers are placed in its pixels
    for panel in drawing.panels:
        panel.place_labels()
    return drawing


def _helicopter_picture(
    session: QuerySession, snapshot: MapSnapshot, result: SessionPlan, geometry: PlanGeometry
) -> PlanDrawing:
    """The helicopter's figure: top view, one legend for both views, side view; sized to the top view.

    The figure is :data:`HELI_WIDTH` inches wide; its height gives the top view the aspect of its area
    (the width left beside the axis labels and colour bars, :data:`HELI_TOP_MARGIN`, times the area's
    height over its width) plus the fixed rows (:data:`HELI_ROWS`: top view labels, legend, side view).
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(HELI_WIDTH, 12.0), dpi=DPI, layout="constrained")
    top, key, side = fig.subplots(3, 1)
    drawing = PlanDrawing(fig, top, side)
    view = PanelView(top, TOP, drawing)
    drawing.panels.append(view)
    wires = helicopter_top(fig, view, session, snapshot, result, geometry)
    drawing.counts["crossings"] = helicopter_side(side, session, snapshot, result, geometry, wires)
    key.axis("off")
    key.legend(*legend_entries(view, side), loc="center", ncol=6, fontsize=8, frameon=False)
    (x0, x1), (y0, y1) = top.get_xlim(), top.get_ylim()
    top_height = (HELI_WIDTH - HELI_TOP_MARGIN) * (y1 - y0) / (x1 - x0) + HELI_ROWS[0]
    top.get_gridspec().set_height_ratios([top_height, *HELI_ROWS[1:]])
    fig.set_size_inches(HELI_WIDTH, top_height + sum(HELI_ROWS[1:]) + HELI_TITLE)
    return drawing


def _targets(path: Path) -> list[Path]:
    """The files to write: ``path`` itself when it ends in .png or .svg, else both (suffix replaced)."""
    if path.suffix.lower() in (".png", ".svg"):
        return [path]
    return [path.with_suffix(".png"), path.with_suffix(".svg")]


def plan_picture(
    session: QuerySession,
    snapshot: MapSnapshot,
    result: SessionPlan,
    path: str | Path,
    *,
    title: str | None = None,
    query_cached: bool = False,
) -> list[Path]:
    """Draw one plan and write it; returns the written files.

    Args:
        session: the session that planned.
        snapshot: the maps it planned on.
        result: its result.
        path: ``*.png`` or ``*.svg`` writes that format; any other suffix (or none) writes both a
            ``.png`` and an ``.svg`` next to it, as the benchmark figures do. PNGs are 150 dpi.
        title: first title line (see :func:`draw_plan_picture`).
        query_cached: the query's library and tree were reused from the planner's query cache.

    Raises:
        PictureError: matplotlib is not installed, or a file cannot be written.
    """
    drawing = draw_plan_picture(session, snapshot, result, title=title, query_cached=query_cached)
    import matplotlib

    written: list[Path] = []
    with matplotlib.rc_context({"svg.hashsalt": "drd_planner"}):
        for target in _targets(Path(path)):
            svg = target.suffix.lower() == ".svg"
            metadata: dict[str, Any] = {"Date": None, "Creator": None} if svg else {"Software": None}
            try:
                target.parent.mkdir(parents=True, exist_ok=True)
                drawing.figure.savefig(target, dpi=DPI, metadata=metadata, bbox_inches="tight", pad_inches=0.1)
            except OSError as exc:
                raise PictureError(f"cannot write the plan picture {target}: {exc}") from exc
            written.append(target)
    return written
