"""What a plan picture draws, in world coordinates (metres): numpy only, no matplotlib.

Outlines of posed shapes projected on a picture plane (:func:`shape_outline`, the convex hull by
:class:`scipy.spatial.ConvexHull`), the polylines of library and checked edges (:func:`edge_points`,
:class:`PlanGeometry`), where wires cross a plan seen from above (:func:`profile_crossings`), and the two
things a picture reads of a domain beyond the session's interface (:func:`domain_robot`,
:func:`vehicle_radius`). The drawing is in :mod:`drd_planner.pictures.plan`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
from scipy.spatial import ConvexHull, QhullError

from drd_planner.arrays import FloatArray
from drd_planner.exceptions import DrdError
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.robot import RobotModel
from drd_planner.geometry.shapes import Box, Capsule, Cylinder, Shape, Sphere, TriangleMesh
from drd_planner.planning.map_state import MapSnapshot
from drd_planner.planning.session import QuerySession
from drd_planner.planning.session_plan import SessionPlan

__all__ = [
    "CIRCLE_POINTS",
    "TOP",
    "PictureError",
    "PlanGeometry",
    "capsule_segment",
    "convex_hull",
    "domain_robot",
    "edge_points",
    "end_states",
    "profile_crossings",
    "shape_outline",
    "shape_points",
    "split_obstacles",
    "vehicle_radius",
]

#: Points on each circle of a cylinder, sphere or capsule outline.
CIRCLE_POINTS = 48
#: (3, 2) projection of the top view: world (x, y, z) -> picture (x, y).
TOP: FloatArray = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]])


class PictureError(DrdError):
    """A plan picture cannot be drawn or written (matplotlib, the ``plots`` extra, missing; a bad path)."""


def capsule_segment(shape: Capsule, pose: Pose) -> FloatArray:
    """(2, 3) world end points (metres) of a capsule's straight part (along its local z)."""
    half = 0.5 * shape.length * pose.rotation()[:, 2]
    return np.stack([pose.position - half, pose.position + half])


def _circle(centre: npt.ArrayLike, u: FloatArray, v: FloatArray, radius: float) -> FloatArray:
    """(CIRCLE_POINTS, 3) points of a circle about ``centre`` in the plane of orthonormal u, v."""
    t = np.linspace(0.0, 2.0 * np.pi, CIRCLE_POINTS, endpoint=False)
    out: FloatArray = np.asarray(centre) + radius * (np.cos(t)[:, None] * u + np.sin(t)[:, None] * v)
    return out


def shape_points(shape: Shape, pose: Pose, plane: FloatArray) -> FloatArray:
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


def convex_hull(points: FloatArray) -> FloatArray:
    """(H, 2) counter-clockwise convex hull of (K, 2) points, from the lowest (x, then y) vertex.

    Points equal to 9 decimals count once; collinear points give the 2 end points, fewer than 3 distinct
    points themselves (sorted).
    """
    pts = np.unique(np.round(points, 9), axis=0)  # sorted by x, then y
    if pts.shape[0] < 3:
        return pts
    try:
        vertices = ConvexHull(pts).vertices  # counter-clockwise in 2-D
    except QhullError:  # all points on one line: its two ends
        return pts[[0, -1]]
    start = int(np.argmin(vertices))  # the lowest row of the sorted points: the lowest (x, y) vertex
    hull: FloatArray = pts[np.roll(vertices, -start)]
    return hull


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
    return convex_hull(shape_points(shape, pose, matrix) @ matrix)


def edge_points(session: QuerySession, edges: Sequence[int], snapshot: MapSnapshot | None = None) -> list[FloatArray]:
    """One (K, 3) polyline (metres, planning frame) per edge, in the order of ``edges``.

    The positions (:meth:`QuerySession.positions`, as the node publishes them) of each edge's
    samples (:meth:`QuerySession.edge_states`): x, y, z for the helicopter, the end effector for the
    arm (of ``snapshot.robot`` when the snapshot carries a ``robot_description``).
    """
    if not edges:
        return []
    states = [session.edge_states(int(e)) for e in edges]
    points = session.positions(np.concatenate(states), snapshot)
    return np.split(points, np.cumsum([len(q) for q in states])[:-1])


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


def along(points: FloatArray) -> FloatArray:
    """(K,) cumulative horizontal distance (metres) along a (K, 2+) polyline."""
    steps = np.linalg.norm(np.diff(points[:, :2], axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(steps)])


def end_states(session: QuerySession, result: SessionPlan) -> tuple[FloatArray, FloatArray]:
    """(D,) start and goal states drawn: the plan's own ends, else the prior's stored query."""
    if result.ok and result.states.shape[0] >= 2:
        return np.asarray(result.states[0]), np.asarray(result.states[-1])
    return session.vertex_state(session.domain.start), session.goal_state


def split_obstacles(snapshot: MapSnapshot) -> tuple[FloatArray, list[tuple[Shape, Pose]]]:
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


class PlanGeometry:
    """What a picture draws of the graph, in world coordinates (metres), computed once.

    Attributes:
        layers: edge ids per layer: ``unchecked`` library edges (sorted), ``free`` and ``blocked``
            checks (check order), ``path`` edges.
        polylines: edge id -> (K, 3) polyline of every library and checked edge.
        plan: (K, 3) the plan's positions (empty without a plan).
    """

    def __init__(self, session: QuerySession, snapshot: MapSnapshot, result: SessionPlan) -> None:
        checked = {c.edge for c in result.checks}
        # The stored query's library, drawn only for a plan of that query (a new query has its own).
        own_query = result.query.startswith("tree:")
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
# What a picture reads of a domain beyond the session's interface


def domain_robot(session: QuerySession) -> RobotModel | None:
    """The domain's robot model (the arm's), or None when it has none."""
    return session.domain.robot


def vehicle_radius(session: QuerySession) -> float:
    """The domain's vehicle radius in metres (the helicopter's), 0 when it has none."""
    return session.domain.vehicle_radius
