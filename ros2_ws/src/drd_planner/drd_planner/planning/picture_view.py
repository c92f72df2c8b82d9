"""The drawing pieces every plan picture shares: styles, the drawn record and one panel's drawing.

:class:`PanelView` draws on one matplotlib axes through a (3, 2) projection of world points (metres):
edge layers with check numbers, wires and solid outlines, start and goal, and the view limits. The
views of each domain (:mod:`~drd_planner.planning.picture_helicopter`,
:mod:`~drd_planner.planning.picture_arm`) are made of them. matplotlib is imported only inside the
drawing methods (the ``plots`` extra).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.bench.extras import install_hint
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.picture_geometry import (
    PictureError,
    PlanGeometry,
    shape_outline,
    shape_points,
    split_obstacles,
)
from drd_planner.planning.session import PlanResult

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure
    from matplotlib.text import Text

__all__ = [
    "EDGE_STYLES",
    "EXTRA_COLOURS",
    "TERRAIN_CMAP",
    "TERRAIN_CMAP_TOP",
    "PanelView",
    "PlanDrawing",
    "require_matplotlib",
]

#: Colours beyond those of :data:`drd_planner.bench.plots.COLOURS` (matplotlib colour specs).
EXTRA_COLOURS = {
    "wire": "#1a1a1a",
    "solid": "#7b3294",
    "terrain_line": "#6b4f2a",
    "terrain_fill": "#c9ad85",
    "arm": "#555555",
}
#: Terrain colour map, of which the light part up to :data:`TERRAIN_CMAP_TOP` is used.
TERRAIN_CMAP = "YlOrBr"
TERRAIN_CMAP_TOP = 0.55
#: Line styles of the edge layers (matplotlib LineCollection keywords), in drawing order.
EDGE_STYLES: dict[str, dict[str, Any]] = {
    "unchecked": {"linewidths": 0.6, "alpha": 0.55, "zorder": 3, "label": "library edge, not checked"},
    "path": {"linewidths": 7.0, "alpha": 0.55, "zorder": 4, "capstyle": "round", "label": "plan"},
    "free": {"linewidths": 1.8, "zorder": 5, "label": "checked free"},
    "blocked": {"linewidths": 1.8, "zorder": 6, "label": "checked blocked"},
}


@dataclass
class PlanDrawing:
    """A drawn plan picture.

    Attributes:
        figure: the matplotlib figure (Agg canvas attached).
        top: the top-view axes; ``side`` the side-view axes.
        layers: the top view's edge layers (``unchecked``, ``path``, ``free``, ``blocked``); one polyline
            per edge, except ``path``: the whole plan as one polyline (none without a plan).
        labels: the check numbers written on the top view, in check order.
        counts: what the top view drew: ``unchecked``, ``free``, ``blocked``, ``path`` (edges), ``wires``
            (capsule segments), ``solids`` (outlines), ``labels``; and ``crossings`` (wire crossings marked
            in the helicopter's side view).
    """

    figure: Figure
    top: Axes
    side: Axes
    layers: dict[str, LineCollection] = field(default_factory=dict)
    labels: list[Text] = field(default_factory=list)
    counts: dict[str, int] = field(default_factory=dict)


def require_matplotlib() -> None:
    """Raise PictureError when matplotlib (the ``plots`` extra) is not installed."""
    try:
        import matplotlib  # noqa: F401
    except ImportError as exc:
        raise PictureError(
            f"plan pictures need the 'plots' extra (matplotlib): {install_hint('plots')}"
        ) from exc


class PanelView:
    """One panel: its axes, its (3, 2) projection and, for the top view, the record of what it drew."""

    def __init__(self, ax: Axes, plane: FloatArray, record: PlanDrawing | None) -> None:
        self.ax = ax
        self.plane = plane
        self.record = record

    def project(self, points: FloatArray) -> FloatArray:
        """(K, 2) picture coordinates of (K, 3) world points."""
        out: FloatArray = points @ self.plane
        return out

    def edges(self, geometry: PlanGeometry, result: PlanResult) -> None:
        """Draw the edge layers and each check's number (1 = first) at the middle of its edge."""
        from matplotlib.collections import LineCollection

        from drd_planner.bench.plots import COLOURS

        for key, style in EDGE_STYLES.items():
            ids = geometry.layers[key]
            if key == "path":
                lines = [geometry.plan] if geometry.plan.shape[0] else []
            else:
                lines = [geometry.polylines[e] for e in ids]
            label = style["label"] if lines else None
            coll = LineCollection(
                [self.project(line) for line in lines], colors=COLOURS[key], **{**style, "label": label}
            )
            coll.set_gid(f"{key}_edges")
            self.ax.add_collection(coll)
            if self.record is not None:
                self.record.layers[key] = coll
                self.record.counts[key] = len(ids)
        for number, check in enumerate(result.checks, start=1):
            line = geometry.polylines[check.edge]
            x, y = (float(v) for v in self.project(line[line.shape[0] // 2]))
            text = self.ax.text(
                x,
                y,
                str(number),
                fontsize=7,
                ha="center",
                va="center",
                color=COLOURS["free" if check.free else "blocked"],
                fontweight="bold",
                zorder=10,
                bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.8},
            )
            if self.record is not None:
                self.record.labels.append(text)
        if self.record is not None:
            self.record.counts["labels"] = len(self.record.labels)

    def obstacles(self, snapshot: MapSnapshot, *, solid_label: str, min_size: float = 0.0) -> FloatArray:
        """Draw wires as dark lines and solid outlines as translucent fills; return (C, 2, 3) wire segments.

        Outlines narrower than ``min_size`` (metres; towers seen from far) also get a dot, to stay visible.
        """
        from matplotlib.collections import LineCollection
        from matplotlib.patches import Polygon

        wires, solids = split_obstacles(snapshot)
        if wires.shape[0]:
            segments = [self.project(segment) for segment in wires]
            coll = LineCollection(
                segments, colors=EXTRA_COLOURS["wire"], linewidths=1.4, zorder=7, label="wire"
            )
            coll.set_gid("wires")
            self.ax.add_collection(coll)
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
                zorder=2,
                label=solid_label if drawn == 0 else None,
            )
            self.ax.add_patch(patch)
            if float(np.max(np.ptp(outline, axis=0))) < min_size:
                x, y = (float(v) for v in outline.mean(axis=0))
                self.ax.plot(x, y, "o", color=EXTRA_COLOURS["solid"], markersize=3, zorder=2)
            drawn += 1
        if self.record is not None:
            self.record.counts["wires"] = int(wires.shape[0])
            self.record.counts["solids"] = drawn
        return wires

    def endpoints(self, start: FloatArray, goal: FloatArray) -> None:
        """Start (black circle) and goal (black star) at (3,) world points."""
        (sx, sy), (gx, gy) = self.project(start), self.project(goal)
        self.ax.plot(sx, sy, "o", color="black", markersize=8, zorder=9, label="start")
        self.ax.plot(gx, gy, "*", color="black", markersize=14, zorder=9, label="goal")

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
