"""A picture of one plan: the maps, the library, every check (green free, red blocked) and the plan.

:func:`plan_picture` writes it (PNG and/or SVG); :func:`draw_plan_picture` returns the figure with what
it drew, so tests can compare the picture with its data. Two panels:

- **helicopter** (x, y, z metres first in the states; :mod:`~drd_planner.planning.picture_helicopter`):
  a *top view* with the terrain heights (shaded, with contour lines and a colour bar; unknown cells
  blank), wires (obstacles made only of capsules) as dark lines, every other solid (no-fly zones,
  towers: boxes, cylinders, spheres, meshes) as a translucent footprint, the library edges not checked in
  light grey, the checked edges green / red with their check number (1 = first) at the middle, the plan
  as a wide blue band, start and goal; and a *side view*: altitude along the plan's horizontal distance
  with the vehicle radius around it, the terrain profile under it and the heights of the wires where the
  plan passes over or under them. Without a plan the side view runs along the straight start-goal line
  and shows the checked edges projected onto it.
- **arm** (``session.domain.name == "arm"``; :mod:`~drd_planner.planning.picture_arm`): the
  end-effector paths (:meth:`PlanningSession.positions` of each edge's joint samples, the positions the
  node publishes) in a top view (x, y) and a side view (the vertical plane through the start-goal
  direction of the end effector), with the obstacles' outlines projected onto each plane and the arm (its
  joint frames) drawn at its start and goal.

What is drawn is computed in world coordinates (numpy only) by
:mod:`~drd_planner.planning.picture_geometry`; the drawing pieces every view shares are in
:mod:`~drd_planner.planning.picture_view`.

matplotlib is the optional ``plots`` extra: it is imported when a picture is drawn, through its Agg
canvas only (no pyplot, nothing global), and a missing install raises :class:`PictureError`. The
same inputs give the same bytes (no dates or software tags, fixed SVG ids).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.picture_arm import arm_views
from drd_planner.planning.picture_geometry import TOP, AnySession, PictureError, PlanGeometry
from drd_planner.planning.picture_helicopter import helicopter_side, helicopter_top
from drd_planner.planning.picture_view import PanelView, PlanDrawing, require_matplotlib
from drd_planner.planning.session import PlanResult

__all__ = ["PictureError", "PlanDrawing", "draw_plan_picture", "plan_picture"]


def _title(session: AnySession, result: PlanResult, title: str | None) -> str:
    """The figure title: the given one, else tree, map version, outcome (the reason when there is no plan)."""
    if title is not None:
        return title
    head = f"{session.name} (map v{result.map_version})"
    return f"{head}: {result.message}" if result.ok else f"{head}: NO PLAN - {result.message}"


def draw_plan_picture(
    session: AnySession, snapshot: MapSnapshot, result: PlanResult, *, title: str | None = None
) -> PlanDrawing:
    """Draw one plan (or a failed request) on a new figure; see the module docstring.

    Args:
        session: the session that planned (its domain, library and edge geometry).
        snapshot: the maps it planned on.
        result: its result (checks in order; path edges and states when ok).
        title: figure title (default: tree, map version, outcome or why there is no plan).

    Raises:
        PictureError: matplotlib is not installed.
    """
    require_matplotlib()
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    geometry = PlanGeometry(session, snapshot, result)
    if session.domain.name == "arm":
        fig = Figure(figsize=(13.0, 6.2), layout="constrained")
        top, side = fig.subplots(1, 2)
        drawing = PlanDrawing(fig, top, side)
        arm_views(top, side, session, snapshot, result, geometry, drawing)
    else:
        fig = Figure(figsize=(10.0, 11.0), layout="constrained")
        top, side = fig.subplots(2, 1, height_ratios=[3.0, 1.25])
        drawing = PlanDrawing(fig, top, side)
        wires = helicopter_top(fig, PanelView(top, TOP, drawing), session, snapshot, result, geometry)
        drawing.counts["crossings"] = helicopter_side(side, session, snapshot, result, geometry, wires)
    FigureCanvasAgg(fig)
    free = len(result.checks) - result.num_blocked
    summary = (
        f"{len(result.checks)} checks: {free} free (green), {result.num_blocked} blocked (red); "
        "numbers give the check order"
    )
    fig.suptitle(f"{_title(session, result, title)}\n{summary}", fontsize=11)
    return drawing


def _targets(path: Path) -> list[Path]:
    """The files to write: ``path`` itself when it ends in .png or .svg, else both (suffix replaced)."""
    if path.suffix.lower() in (".png", ".svg"):
        return [path]
    return [path.with_suffix(".png"), path.with_suffix(".svg")]


def plan_picture(
    session: AnySession,
    snapshot: MapSnapshot,
    result: PlanResult,
    path: str | Path,
    *,
    title: str | None = None,
) -> list[Path]:
    """Draw one plan and write it; returns the written files.

    Args:
        session: the session that planned.
        snapshot: the maps it planned on.
        result: its result.
        path: ``*.png`` or ``*.svg`` writes that format; any other suffix (or none) writes both a
            ``.png`` and an ``.svg`` next to it, as the benchmark figures do. PNGs are 150 dpi.
        title: figure title (see :func:`draw_plan_picture`).

    Raises:
        PictureError: matplotlib is not installed, or a file cannot be written.
    """
    drawing = draw_plan_picture(session, snapshot, result, title=title)
    import matplotlib

    written: list[Path] = []
    with matplotlib.rc_context({"svg.hashsalt": "drd_planner"}):
        for target in _targets(Path(path)):
            svg = target.suffix.lower() == ".svg"
            metadata: dict[str, Any] = {"Date": None, "Creator": None} if svg else {"Software": None}
            try:
                target.parent.mkdir(parents=True, exist_ok=True)
                drawing.figure.savefig(target, dpi=150, metadata=metadata)
            except OSError as exc:
                raise PictureError(f"cannot write the plan picture {target}: {exc}") from exc
            written.append(target)
    return written
