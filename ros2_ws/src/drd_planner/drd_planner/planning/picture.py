"""A picture of one plan: the maps, the library, every check (green free, red blocked) and the plan.

:func:`plan_picture` writes it (PNG and/or SVG); :func:`draw_plan_picture` returns the figure with what
it drew, so tests can compare the picture with its data. Two panels:

- **helicopter** (x, y, z metres first in the states): a *top view* with the terrain heights (shaded, with
  contour lines and a colour bar; unknown cells blank), wires (obstacles made only of capsules) as dark
  lines, every other solid (no-fly zones, towers: boxes, cylinders, spheres, meshes) as a translucent
  footprint, the library edges not checked in light grey, the checked edges green / red with their check
  number (1 = first) at the middle, the plan as a wide blue band, start and goal; and a *side view*:
  altitude along the plan's horizontal distance with the vehicle radius around it, the terrain profile
  under it and the heights of the wires where the plan passes over or under them. Without a plan the side
  view runs along the straight start-goal line and shows the checked edges projected onto it.
- **arm** (``session.domain.name == "arm"``): the end-effector paths (:meth:`PlanningSession.positions`
  of each edge's joint samples, the positions the node publishes) in a top view (x, y) and a side view
  (the vertical plane through the start-goal direction of the end effector), with the obstacles'
  outlines projected onto each plane and the arm (its joint frames) drawn at its start and goal.

matplotlib is the optional ``plots`` extra: it is imported when a picture is drawn, through its Agg
canvas only (no pyplot, nothing global), and a missing install raises :class:`PictureError`. The
same inputs give the same bytes (no dates or software tags, fixed SVG ids).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.exceptions import DrdError
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Box, Capsule, Cylinder, Shape, Sphere, TriangleMesh
from drd_planner.geometry.terrain import Heightfield
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.query_session import QueryPlanResult, QuerySession
from drd_planner.planning.session import PlanningSession, PlanResult

#: A session of one tree, or of a whole prior: what a picture reads of them is the same.
AnySession = PlanningSession | QuerySession

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure
    from matplotlib.text import Text


__all__ = [
    "TOP",
    "PictureError",
    "PlanDrawing",
    "capsule_segment",
    "draw_plan_picture",
    "edge_points",
    "plan_picture",
    "profile_crossings",
    "shape_outline",
]

#: Points on each circle of a cylinder, sphere or capsule outline.
CIRCLE_POINTS = 48
#: (3, 2) projection of the top view: world (x, y, z) -> picture (x, y).
TOP: FloatArray = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]])
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


class PictureError(DrdError):
    """A plan picture cannot be drawn or written (matplotlib, the ``plots`` extra, missing; a bad path)."""


# --------------------------------------------------------------------------------------------------
# Geometry (numpy only)


def capsule_segment(shape: Capsule, pose: Pose) -> FloatArray:
    """(2, 3) world end points (metres) of a capsule's straight part (along its local z)."""
    half = 0.5 * shape.length * pose.rotation()[:, 2]
    return np.stack([pose.position - half, pose.position + half])


def _circle(centre: npt.ArrayLike, u: FloatArray, v: FloatArray, radius: float) -> FloatArray:
    """(CIRCLE_POINTS, 3) points of a circle about ``centre`` in the plane of orthonormal u, v."""
    t = np.linspace(0.0, 2.0 * np.pi, CIRCLE_POINTS, endpoint=False)
    out: FloatArray = np.asarray(centre) + radius * (np.cos(t)[:, None] * u + np.sin(t)[:, None] * v)
    return out


def _shape_points(shape: Shape, pose: Pose, plane: FloatArray) -> FloatArray:
    """(K, 3) world points whose projection by ``plane`` (3, 2) has the shape's outline as its hull."""
    if isinstance(shape, Box):
        corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)
        return pose.transform_points(0.5 * corners * shape.size)
    if isinstance(shape, TriangleMesh):
        return pose.transform_points(shape.vertices)
    u, v = plane[:, 0], plane[:, 1]  # round shapes: circles in the picture plane, rims for cylinders
    if isinstance(shape, Sphere):
        return _circle(pose.position, u, v, shape.radius)
    rot = pose.rotation()
    half = 0.5 * shape.length * rot[:, 2]
    ends = (pose.position - half, pose.position + half)
    if isinstance(shape, Capsule):
        return np.concatenate([_circle(e, u, v, shape.radius) for e in ends])
    if isinstance(shape, Cylinder):
        return np.concatenate([_circle(e, rot[:, 0], rot[:, 1], shape.radius) for e in ends])
    raise PictureError(f"cannot draw a {type(shape).__name__}")


def _convex_hull(points: FloatArray) -> FloatArray:
    """(H, 2) counter-clockwise convex hull of (K, 2) points (monotone chain; 2 rows if collinear)."""
    pts = np.unique(np.round(points, 9), axis=0)
    if pts.shape[0] < 3:
        return pts

    def half(rows: Sequence[FloatArray]) -> list[FloatArray]:
        chain: list[FloatArray] = []
        for p in rows:
            while len(chain) >= 2:
                a, b = chain[-2], chain[-1]
                if (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) > 0:
                    break
                chain.pop()
            chain.append(p)
        return chain

    rows = list(pts)
    return np.array(half(rows)[:-1] + half(rows[::-1])[:-1])


def shape_outline(shape: Shape, pose: Pose, *, plane: npt.ArrayLike = TOP) -> FloatArray:
    """(H, 2) outline (metres) of a posed shape projected by ``plane``.

    Args:
        shape: the part's shape.
        pose: its pose in the planning frame.
        plane: (3, 2) orthonormal columns u, v: a world point p is drawn at (p . u, p . v); default the
            top view (x, y).

    Returns:
        The convex hull of the projection: exact for boxes, and for spheres, cylinders and capsules up to
        :data:`CIRCLE_POINTS` per circle; the hull of a mesh. Two rows for a shape seen edge-on.
    """
    matrix = np.asarray(plane, dtype=np.float64)
    return _convex_hull(_shape_points(shape, pose, matrix) @ matrix)


def edge_points(
    session: AnySession, edges: Sequence[int], snapshot: MapSnapshot | None = None
) -> list[FloatArray]:
    """One (K, 3) polyline (metres, planning frame) per edge, in the order of ``edges``.

    The positions (:meth:`PlanningSession.positions`, as the node publishes them) of each edge's
    samples (:meth:`PlanningSession.edge_states`): x, y, z for the helicopter, the end effector for the
    arm (of ``snapshot.robot`` when the snapshot carries a ``robot_description``).
    """
    if not edges:
        return []
    states = [session.edge_states(int(e)) for e in edges]
    points = session.positions(np.concatenate(states), snapshot)
    return np.split(points, np.cumsum([len(q) for q in states])[:-1])


def _arm_skeleton(session: AnySession, snapshot: MapSnapshot, q: FloatArray) -> FloatArray:
    """(D + 2, 3) joint-frame origins and the end effector (metres) of one (D,) arm configuration."""
    from drd_planner.geometry.robot import RobotModel

    robot = snapshot.robot if snapshot.robot is not None else getattr(session.domain, "robot", None)
    if not isinstance(robot, RobotModel):
        raise PictureError(f"{session.name}: the arm domain has no robot model to draw")
    origins = robot.fk.frames(q)[0, :, :3, 3]
    return np.vstack([origins, session.positions(q, snapshot)])


def profile_crossings(reference: FloatArray, segments: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Where 3-D segments cross a reference polyline, seen from above.

    Args:
        reference: (K, 2+) polyline; only x, y are used (metres).
        segments: (C, 2, 3) segment end points (metres), e.g. wire capsules.

    Returns:
        (s, z): (N,) horizontal distance along ``reference`` of each crossing and (N,) the segment's
        height there (metres), sorted by s.
    """
    if reference.shape[0] < 2 or segments.shape[0] == 0:
        return np.zeros(0), np.zeros(0)
    p, q = reference[:-1, :2], reference[1:, :2]  # (K-1, 2)
    a, b = segments[:, 0], segments[:, 1]  # (C, 3)
    r = (q - p)[:, None, :]  # (K-1, 1, 2)
    w = (b - a)[None, :, :2]  # (1, C, 2)
    d = a[None, :, :2] - p[:, None, :]  # (K-1, C, 2)
    denom = r[..., 0] * w[..., 1] - r[..., 1] * w[..., 0]
    ok = np.abs(denom) > 1e-12
    safe = np.where(ok, denom, 1.0)
    t = (d[..., 0] * w[..., 1] - d[..., 1] * w[..., 0]) / safe
    u = (d[..., 0] * r[..., 1] - d[..., 1] * r[..., 0]) / safe
    k, c = np.nonzero(ok & (t >= 0.0) & (t <= 1.0) & (u >= 0.0) & (u <= 1.0))
    lengths = np.linalg.norm(q - p, axis=1)
    s = np.concatenate([[0.0], np.cumsum(lengths)])[k] + t[k, c] * lengths[k]
    z = a[c, 2] + u[k, c] * (b[c, 2] - a[c, 2])
    order = np.argsort(s, kind="stable")
    return s[order], z[order]


def _along(points: FloatArray) -> FloatArray:
    """(K,) cumulative horizontal distance (metres) along a (K, 2+) polyline."""
    steps = np.linalg.norm(np.diff(points[:, :2], axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(steps)])


def end_states(session: AnySession, result: PlanResult) -> tuple[FloatArray, FloatArray]:
    """(D,) start and goal states drawn: the plan's own ends, else the prior's stored query."""
    if result.ok and result.states.shape[0] >= 2:
        return np.asarray(result.states[0]), np.asarray(result.states[-1])
    return session.vertex_state(session.domain.start), session.goal_state


def _split_obstacles(snapshot: MapSnapshot) -> tuple[FloatArray, list[tuple[Shape, Pose]]]:
    """((C, 2, 3) capsule segments of the wires, [(shape, pose)] of every other part), in key order.

    A wire is an obstacle whose parts are all capsules (a LINE_STRIP marker).
    """
    wires: list[FloatArray] = []
    solids: list[tuple[Shape, Pose]] = []
    for key in sorted(snapshot.obstacles):
        parts = snapshot.obstacles[key]
        if parts and all(isinstance(shape, Capsule) for shape, _ in parts):
            wires.extend(capsule_segment(shape, pose) for shape, pose in parts if isinstance(shape, Capsule))
        else:
            solids.extend(parts)
    return (np.stack(wires) if wires else np.zeros((0, 2, 3))), solids


class _Geometry:
    """What a picture draws of the graph, in world coordinates (metres), computed once.

    Attributes:
        layers: edge ids per layer: ``unchecked`` library edges (sorted), ``free`` and ``blocked``
            checks (check order), ``path`` edges.
        polylines: edge id -> (K, 3) polyline of every library and checked edge.
        plan: (K, 3) the plan's positions (empty without a plan).
    """

    def __init__(self, session: AnySession, snapshot: MapSnapshot, result: PlanResult) -> None:
        checked = {c.edge for c in result.checks}
        # The stored query's library, drawn only for a plan of that query (a new query has its own).
        own_query = not isinstance(result, QueryPlanResult) or result.query.startswith("tree:")
        library = np.asarray(session.library_edges() if own_query else (), dtype=np.int64)
        self.layers: dict[str, list[int]] = {
            "unchecked": sorted(int(e) for e in library if int(e) not in checked),
            "free": [c.edge for c in result.checks if c.free],
            "blocked": [c.edge for c in result.checks if not c.free],
            "path": list(result.path_edges),
        }
        edges = self.layers["unchecked"] + self.layers["free"] + self.layers["blocked"]
        self.polylines = dict(zip(edges, edge_points(session, edges, snapshot), strict=True))
        planned = result.ok and result.states.shape[0] >= 2
        self.plan: FloatArray = session.positions(result.states, snapshot) if planned else np.zeros((0, 3))

    def points(self) -> FloatArray:
        """(N, 3) every point of every drawn edge (for the view limits)."""
        lines = list(self.polylines.values())
        return np.concatenate(lines) if lines else np.zeros((0, 3))


# --------------------------------------------------------------------------------------------------
# The drawing


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


def _require_matplotlib() -> None:
    """Raise PictureError when matplotlib (the ``plots`` extra) is not installed."""
    try:
        import matplotlib  # noqa: F401
    except ImportError as exc:
        raise PictureError(
            "plan pictures need matplotlib: pip install 'drd_planner[plots]' (or matplotlib>=3.6)"
        ) from exc


class _View:
    """One panel: its axes, its (3, 2) projection and, for the top view, the record of what it drew."""

    def __init__(self, ax: Axes, plane: FloatArray, record: PlanDrawing | None) -> None:
        self.ax = ax
        self.plane = plane
        self.record = record

    def project(self, points: FloatArray) -> FloatArray:
        """(K, 2) picture coordinates of (K, 3) world points."""
        out: FloatArray = points @ self.plane
        return out

    def edges(self, geometry: _Geometry, result: PlanResult) -> None:
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

        wires, solids = _split_obstacles(snapshot)
        if wires.shape[0]:
            segments = [self.project(segment) for segment in wires]
            coll = LineCollection(
                segments, colors=EXTRA_COLOURS["wire"], linewidths=1.4, zorder=7, label="wire"
            )
            coll.set_gid("wires")
            self.ax.add_collection(coll)
        # Lower solids first, so what stands on something is drawn over it.
        tops = [float(np.max(_shape_points(s, p, self.plane)[:, 2])) for s, p in solids]
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


def _terrain_top(fig: Figure, ax: Axes, terrain: Heightfield) -> None:
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
            zorder=1,
        )
        ax.clabel(lines, fontsize=6, fmt="%.0f m", inline=True)
    bar = fig.colorbar(image, ax=ax, shrink=0.8, pad=0.02)
    bar.set_label("terrain height (m)")


def _helicopter_top(
    fig: Figure,
    view: _View,
    session: AnySession,
    snapshot: MapSnapshot,
    result: PlanResult,
    geometry: _Geometry,
) -> FloatArray:
    """The helicopter's top view; returns the wire segments."""
    if snapshot.terrain is not None:
        _terrain_top(fig, view.ax, snapshot.terrain)
    start, goal = (state[:3] for state in end_states(session, result))
    points = np.vstack([geometry.points(), start, goal])
    span = float(np.max(np.ptp(points[:, :2], axis=0)))
    wires = view.obstacles(snapshot, solid_label="no-fly zone / tower", min_size=0.01 * span)
    view.edges(geometry, result)
    view.endpoints(start, goal)
    view.fit(points, pad=0.06)
    view.ax.set_xlabel("x (m)")
    view.ax.set_ylabel("y (m)")
    view.ax.set_title("top view", fontsize=10)
    view.ax.legend(fontsize=8, loc="upper left", framealpha=0.9)
    return wires


def _helicopter_side(
    ax: Axes,
    session: AnySession,
    snapshot: MapSnapshot,
    result: PlanResult,
    geometry: _Geometry,
    wires: FloatArray,
) -> int:
    """The side view: altitude along the plan (or along the start-goal line without one); returns the crossings."""
    from drd_planner.bench.plots import COLOURS

    start, goal = (state[:3] for state in end_states(session, result))
    planned = geometry.plan.shape[0] >= 2
    if planned:
        reference = geometry.plan
        ax.set_xlabel("horizontal distance along the plan (m)")
    else:
        steps = max(2, int(np.linalg.norm(goal[:2] - start[:2]) / 5.0) + 1)
        reference = start + np.linspace(0.0, 1.0, steps)[:, None] * (goal - start)
        ax.set_xlabel("horizontal distance along the start-goal line (m)")
    s = _along(reference)
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
        radius = float(getattr(session.domain, "vehicle_radius", 0.0))
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
        ax.plot(
            cross_s, cross_z, "X", color=EXTRA_COLOURS["wire"], markersize=8, zorder=6, label="wire crossing"
        )
        heights.extend(cross_z.tolist())
    low, high = min(heights), max(heights)
    ax.set_xlim(float(s[0]), float(s[-1]))
    ax.set_ylim(low - 10.0, high + 0.2 * (high - low) + 10.0)
    ax.set_ylabel("altitude (m)")
    ax.set_title("side view", fontsize=10)
    ax.grid(True, linewidth=0.3, alpha=0.5)
    ax.legend(fontsize=8, loc="upper right", ncol=3, framealpha=0.9)
    return int(cross_s.size)


def _arm_views(
    top: Axes,
    side: Axes,
    session: AnySession,
    snapshot: MapSnapshot,
    result: PlanResult,
    geometry: _Geometry,
    drawing: PlanDrawing,
) -> None:
    """The arm's top (x, y) and side (vertical plane through start -> goal) views of the end effector."""
    start, goal = end_states(session, result)
    skeletons = {
        "start": _arm_skeleton(session, snapshot, start),
        "goal": _arm_skeleton(session, snapshot, goal),
    }
    heading = skeletons["goal"][-1, :2] - skeletons["start"][-1, :2]
    norm = float(np.linalg.norm(heading))
    across = np.array([heading[0] / norm, heading[1] / norm, 0.0]) if norm > 1e-6 else np.eye(3)[0]
    side_plane = np.stack([across, np.eye(3)[2]], axis=1)
    points = np.concatenate([geometry.points(), *skeletons.values()])
    _, solids = _split_obstacles(snapshot)
    for ax, plane in ((top, TOP), (side, side_plane)):
        view = _View(ax, plane, drawing if ax is top else None)
        view.obstacles(snapshot, solid_label="obstacle")
        view.edges(geometry, result)
        for key, bones in skeletons.items():
            x, y = view.project(bones).T
            style = "-o" if key == "start" else "--o"
            ax.plot(
                x,
                y,
                style,
                color=EXTRA_COLOURS["arm"],
                lw=1.2,
                ms=3,
                alpha=0.8,
                zorder=7,
                label=f"arm at {key}",
            )
        view.endpoints(skeletons["start"][-1], skeletons["goal"][-1])
        outlines = [_shape_points(s, p, plane) for s, p in solids]
        view.fit(np.concatenate([points, *outlines]), pad=0.05)
        ax.grid(True, linewidth=0.3, alpha=0.5)
    top.set_xlabel("x (m)")
    top.set_ylabel("y (m)")
    top.set_title("end effector, top view", fontsize=10)
    side.axhline(0.0, color="black", linewidth=0.8, zorder=1)
    side.set_xlabel("horizontal position along the start -> goal direction (m)")
    side.set_ylabel("z (m)")
    side.set_title("end effector, side view", fontsize=10)
    side.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), framealpha=0.9)


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
    _require_matplotlib()
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    geometry = _Geometry(session, snapshot, result)
    if session.domain.name == "arm":
        fig = Figure(figsize=(13.0, 6.2), layout="constrained")
        top, side = fig.subplots(1, 2)
        drawing = PlanDrawing(fig, top, side)
        _arm_views(top, side, session, snapshot, result, geometry, drawing)
    else:
        fig = Figure(figsize=(10.0, 11.0), layout="constrained")
        top, side = fig.subplots(2, 1, height_ratios=[3.0, 1.25])
        drawing = PlanDrawing(fig, top, side)
        wires = _helicopter_top(fig, _View(top, TOP, drawing), session, snapshot, result, geometry)
        drawing.counts["crossings"] = _helicopter_side(side, session, snapshot, result, geometry, wires)
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
