"""The drawing pieces every plan picture shares: styles, the drawn record and one panel's drawing.

:class:`PanelView` draws on one matplotlib axes through a (3, 2) projection of world points (metres):
edge layers (plain, or coloured by altitude with each checked edge in a casing of its outcome's colour),
wires and solid outlines, start and goal, and the view limits; it keeps what it drew as obstacles and
the check numbers to write, which :meth:`PanelView.place_labels` puts where they hide no obstacle
(:mod:`~drd_planner.pictures.labels`) once the figure's layout is fixed. The views of each
domain (:mod:`~drd_planner.pictures.helicopter`, :mod:`~drd_planner.pictures.arm`) are
made of them. matplotlib is imported only inside the drawing methods (the ``plots`` extra).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.pictures.geometry import (
    PictureError,
    PlanGeometry,
    shape_outline,
    shape_points,
    split_obstacles,
)
from drd_planner.pictures.labels import LabelPlacer, PendingLabel
from drd_planner.pictures.style import (
    COLOURS,
    EXTRA_COLOURS,
    PLOTS_INSTALL_HINT,
)
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.session_plan import SessionPlan

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes
    from matplotlib.cm import ScalarMappable
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure
    from matplotlib.text import Text

__all__ = [
    "CASING_WIDTH",
    "EDGE_STYLES",
    "OBSTACLE_ZORDER",
    "PanelView",
    "PlanDrawing",
    "legend_entries",
    "require_matplotlib",
]

#: Line styles of the edge layers (matplotlib LineCollection keywords), in drawing order.
EDGE_STYLES: dict[str, dict[str, Any]] = {
    "unchecked": {"linewidths": 0.6, "alpha": 0.55, "zorder": 3, "label": "library edge, not checked"},
    "path": {"linewidths": 7.0, "alpha": 0.55, "zorder": 4, "capstyle": "round", "label": "plan"},
    "free": {"linewidths": 1.8, "zorder": 5, "label": "checked free"},
    "blocked": {"linewidths": 1.8, "zorder": 6, "label": "checked blocked"},
}
#: Width (points) of a checked edge's casing when its line is coloured by altitude; the line keeps 1.8.
CASING_WIDTH = 4.8
#: Obstacle lines (wires, tower dots) are drawn above the check numbers (zorder 10): never hidden.
OBSTACLE_ZORDER = 11.0
#: Filled footprints: above the terrain's contour labels (zorder 2.5), below the edges.
FILL_ZORDER = 2.8


@dataclass
class PlanDrawing:
    """A drawn plan picture.

    Attributes:
        figure: the matplotlib figure (Agg canvas attached).
        top: the top-view axes; ``side`` the side-view axes.
        layers: the top view's edge layers (``unchecked``, ``path``, ``free``, ``blocked``); one polyline
            per edge, except ``path``: the whole plan as one polyline (none without a plan). With
            altitude colours, ``free`` and ``blocked`` are the casings in the outcome's colour.
        altitude: the layers coloured by altitude (helicopter top view; empty otherwise): ``unchecked``
            and the lines inside the ``free`` and ``blocked`` casings, one polyline per edge, each
            coloured by the mean altitude (m) of its edge (``get_array()``).
        labels: the check numbers written on the top view, in check order (hidden ones included, with
            ``get_visible()`` False).
        panels: the panels that carry check numbers (top view first).
        lift: the top view's (base altitude m, picture units per metre): edges, plan, start and goal are
            drawn ``per_metre * (z - base)`` up the picture (:meth:`PanelView.lifted`).
        counts: what the top view drew: ``unchecked``, ``free``, ``blocked``, ``path`` (edges), ``wires``
            (capsule segments), ``solids`` (outlines), ``labels``, ``labels_moved`` (off their edge, with a
            leader line), ``labels_hidden`` (no free spot); and ``crossings`` (wire crossings marked in
            the helicopter's side view).
    """

    figure: Figure
    top: Axes
    side: Axes
    layers: dict[str, LineCollection] = field(default_factory=dict)
    altitude: dict[str, LineCollection] = field(default_factory=dict)
    labels: list[Text] = field(default_factory=list)
    panels: list[PanelView] = field(default_factory=list)
    counts: dict[str, int] = field(default_factory=dict)
    lift: tuple[float, float] = (0.0, 0.0)


def require_matplotlib() -> None:
    """Raise PictureError when matplotlib (the ``plots`` extra) is not installed."""
    try:
        import matplotlib  # noqa: F401
    except ImportError as exc:
        raise PictureError(f"plan pictures need the 'plots' extra (matplotlib): {PLOTS_INSTALL_HINT}") from exc


def legend_entries(view: PanelView, *more: Axes) -> tuple[list[Any], list[str]]:
    """The legend handles and labels of a panel and more axes, each label once (the first handle wins).

    A cased layer's entry shows its casing with a line of the middle altitude inside.
    """
    handles: list[Any] = []
    labels: list[str] = []
    for ax in (view.ax, *more):
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            if label not in labels:
                handles.append(view.legend_handles.get(label, handle))
                labels.append(label)
    return handles, labels


class PanelView:
    """One panel: its axes, its (3, 2) projection and, for the top view, the record of what it drew.

    Attributes:
        obstacles: the obstacle artists drawn (wires, footprints, tower dots).
        keep_clear: artists the numbers should rather not cover (start and goal).
        pending: the check numbers to write, in check order; ``labels`` the written texts.
        legend_handles: legend label -> the handle to show instead of the drawn artist (casings).
        lift: (base altitude m, picture units per metre): edges, the plan, start and goal are drawn moved
            up the picture by ``per_metre * (z - base)`` (see :meth:`lifted`); (0, 0) draws them in place.
    """

    def __init__(self, ax: Axes, plane: FloatArray, record: PlanDrawing | None) -> None:
        self.ax = ax
        self.plane = plane
        self.record = record
        self.obstacles: list[Artist] = []
        self.keep_clear: list[Artist] = []
        self.pending: list[PendingLabel] = []
        self.labels: list[Text] = []
        self.legend_handles: dict[str, Any] = {}
        self.lift = (0.0, 0.0)

    def project(self, points: FloatArray) -> FloatArray:
        """(K, 2) picture coordinates of (K, 3) world points."""
        out: FloatArray = points @ self.plane
        return out

    def lifted(self, points: FloatArray) -> FloatArray:
        """(K, 2) picture coordinates of (K, 3) points on edges: projected, then lifted by altitude.

        They move up the picture by ``lift`` (base altitude m, picture units per metre above it), so that
        edges over the same ground at other altitudes lie side by side (no lift by default).
        """
        base, per_metre = self.lift
        out = self.project(points)
        out[:, 1] += per_metre * (points[:, 2] - base)
        return out

    def edges(self, geometry: PlanGeometry, result: SessionPlan, heights: ScalarMappable | None = None) -> None:
        """Draw the edge layers and keep each check's number (1 = first) to write on its edge.

        Args:
            geometry: the edges' polylines.
            result: the checks, in order.
            heights: colour map and norm (metres) of edge altitudes; None draws each layer in its colour
                (:data:`drd_planner.pictures.style.COLOURS`). With it, library edges take the colour of their
                mean altitude and each checked edge is that line inside a casing of its outcome's colour.
        """
        for key, style in EDGE_STYLES.items():
            ids = geometry.layers[key]
            if key == "path":
                lines = [geometry.plan] if geometry.plan.shape[0] else []
            else:
                lines = [geometry.polylines[e] for e in ids]
            coll = self._edge_layer(key, lines, {**style, "label": style["label"] if lines else None}, heights)
            if self.record is not None:
                self.record.layers[key] = coll
                self.record.counts[key] = len(ids)
        for number, check in enumerate(result.checks, start=1):
            colour = COLOURS["free" if check.free else "blocked"]
            line = self.lifted(geometry.polylines[check.edge])
            self.pending.append(PendingLabel(str(number), colour, line))

    def _edge_layer(
        self, key: str, lines: list[FloatArray], style: dict[str, Any], heights: ScalarMappable | None
    ) -> LineCollection:
        """Add one edge layer; the collection whose segments are the edges (a casing, when cased)."""
        from matplotlib.collections import LineCollection
        from matplotlib.lines import Line2D

        projected = [self.lifted(line) for line in lines]
        if heights is None or key == "path":
            coll = LineCollection(projected, colors=COLOURS[key], **style)
        elif key == "unchecked":
            coll = LineCollection(projected, cmap=heights.get_cmap(), norm=heights.norm, **style)
            coll.set_array(np.array([float(np.mean(line[:, 2])) for line in lines]))
        else:
            coll = LineCollection(projected, colors=COLOURS[key], **{**style, "linewidths": CASING_WIDTH})
            core = LineCollection(
                projected,
                cmap=heights.get_cmap(),
                norm=heights.norm,
                linewidths=style["linewidths"],
                zorder=style["zorder"] + 0.5,
            )
            core.set_array(np.array([float(np.mean(line[:, 2])) for line in lines]))
            core.set_gid(f"{key}_altitude")
            middle = heights.get_cmap()(0.5)
            self.legend_handles[style["label"]] = (
                Line2D([], [], color=COLOURS[key], linewidth=CASING_WIDTH),
                Line2D([], [], color=middle, linewidth=style["linewidths"]),
            )
            self.ax.add_collection(core)
            if self.record is not None:
                self.record.altitude[key] = core
        coll.set_gid(f"{key}_edges")
        self.ax.add_collection(coll)
        if heights is not None and self.record is not None and key == "unchecked":
            self.record.altitude[key] = coll
        return coll

    def place_labels(self) -> None:
        """Write the pending check numbers where they hide no obstacle (the figure's layout fixed)."""
        placer = LabelPlacer(self.ax, self.obstacles, self.keep_clear)
        self.labels, counts = placer.place(self.pending)
        if self.record is not None:
            self.record.labels = self.labels
            self.record.counts["labels"] = len(self.labels)
            self.record.counts["labels_moved"] = counts["moved"]
            self.record.counts["labels_hidden"] = counts["hidden"]

    def draw_obstacles(self, snapshot: MapSnapshot, *, solid_label: str, min_size: float = 0.0) -> FloatArray:
        """Draw wires as dark lines and solid outlines as translucent fills; return (C, 2, 3) wire segments.

        Outlines narrower than ``min_size`` (metres; towers seen from far) also get a dot, to stay visible.
        """
        from matplotlib.collections import LineCollection
        from matplotlib.patches import Polygon

        wires, solids = split_obstacles(snapshot)
        if wires.shape[0]:
            segments = [self.project(segment) for segment in wires]
            coll = LineCollection(
                segments, colors=EXTRA_COLOURS["wire"], linewidths=1.4, zorder=OBSTACLE_ZORDER, label="wire"
            )
            coll.set_gid("wires")
            self.ax.add_collection(coll)
            self.obstacles.append(coll)
        # Lower solids first, so what stands on something is drawn over it.
        tops = [float(np.max(shape_points(s, p, self.plane)[:, 2])) for s, p in solids]
        drawn = 0
        for k in np.argsort(tops, kind="stable"):
            shape, pose = solids[int(k)]
            outline = shape_outline(shape, pose, plane=self.plane)
            if outline.shape[0] < 2:
                continue
            patch = Polygon(
                outline,
                closed=True,
                facecolor=EXTRA_COLOURS["solid"],
                edgecolor=EXTRA_COLOURS["solid"],
                alpha=0.3,
                linewidth=1.0,
                zorder=FILL_ZORDER + 0.001 * drawn,
                label=solid_label if drawn == 0 else None,
            )
            patch.set_gid("obstacle")
            self.ax.add_patch(patch)
            self.obstacles.append(patch)
            if float(np.max(np.ptp(outline, axis=0))) < min_size:
                x, y = (float(v) for v in outline.mean(axis=0))
                (dot,) = self.ax.plot(x, y, "o", color=EXTRA_COLOURS["solid"], markersize=3, zorder=OBSTACLE_ZORDER)
                dot.set_gid("obstacle_dot")
                self.obstacles.append(dot)
            drawn += 1
        if self.record is not None:
            self.record.counts["wires"] = int(wires.shape[0])
            self.record.counts["solids"] = drawn
        return wires

    def endpoints(self, start: FloatArray, goal: FloatArray) -> None:
        """Start (black circle) and goal (black star) at (3,) world points."""
        (sx, sy), (gx, gy) = self.lifted(np.stack([start, goal]))
        self.keep_clear += self.ax.plot(sx, sy, "o", color="black", markersize=8, zorder=9, label="start")
        self.keep_clear += self.ax.plot(gx, gy, "*", color="black", markersize=14, zorder=9, label="goal")

    def fit(self, points: FloatArray, *, pad: float) -> None:
        """Fit (N, 3) world points with ``pad`` (fraction of the larger span) around them; equal aspect.

        The shorter side spans at least half the longer one, so a straight plan keeps its surroundings.
        """
        xy = self.project(points)
        lo, hi = xy.min(axis=0), xy.max(axis=0)
        longest = float(max(np.max(hi - lo), 1e-9))
        grow = np.maximum(0.5 * longest - (hi - lo), 0.0) / 2.0
        lo, hi = lo - grow, hi + grow
        margin = pad * longest
        self.ax.set_xlim(float(lo[0] - margin), float(hi[0] + margin))
        self.ax.set_ylim(float(lo[1] - margin), float(hi[1] + margin))
        self.ax.set_aspect("equal")
