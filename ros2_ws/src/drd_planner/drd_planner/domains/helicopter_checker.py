"""Edge checking for the helicopter: a sphere swept along each edge's sampled trajectory through a scene.

The vehicle is a sphere of ``radius`` metres; the scene adds its own ``margin``. An edge is free when the
sphere (radius + margin) placed at every trajectory sample touches no obstacle and no sample lies under
the terrain (exactly :meth:`Scene.sphere_sweep_free`). Samples are at most the vehicle radius apart along
the edge, so the spheres overlap and a thin wire cannot slip between two of them unnoticed.

:class:`HelicopterChecker` is what the node and the dataset builder both use. ``check(edge)`` is one
sweep (bisection order, early exit). ``check_many(edges)`` gives the same answers faster:

1. the below-terrain test on all samples of all edges at once (numpy);
2. a conservative numpy prefilter drops samples that cannot touch anything: their sphere is above the
   highest corner of the terrain's collision surface around them (the scene's own terrain rule, with a
   wider window; unknown heights filled as the heightfield's ``unknown`` option says) and outside
   every obstacle's margin-inflated bounding box (binned on a 3D grid of :data:`BIN_SIZE` metres); the
   boxes come from the world description (:func:`obstacle_boxes`) - without them every sample is kept;
3. the remaining samples go to the scene's vectorised sphere query (numpy AABB prefilter, FCL on near
   pairs) in rounds of bisection rank (the middle samples of all open edges first), and an edge is
   dropped at its first hit.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.aabb import shape_aabb
from drd_planner.geometry.ordering import bisection_rank
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Shape
from drd_planner.geometry.terrain import Heightfield
from drd_planner.geometry.terrain_collider import cell_maxima, window_max

__all__ = ["HelicopterChecker", "helicopter_checker", "obstacle_boxes"]

#: Samples handed to one vectorised scene query (bounds the (K, N) prefilter arrays).
CHUNK_POINTS = 4096
#: Bin size (metres) of the obstacle-box occupancy grid of the prefilter.
BIN_SIZE = 10.0
#: Obstacles named in one explanation at most (the rest are counted).
MAX_CAUSES = 4


class _NearFilter:
    """Conservative numpy test: which spheres might touch the terrain surface or an obstacle box.

    Args:
        terrain: the scene's heightfield, or None.
        boxes: ``(lo, hi)`` (N, 3) obstacle AABBs in metres (without margin), or None when unknown.
        reach: sphere radius plus the scene margin, metres.
        points: (P, 3) every sample that will be asked about (sets the grid extent), metres.
    """

    def __init__(
        self,
        terrain: Heightfield | None,
        boxes: tuple[FloatArray, FloatArray] | None,
        reach: float,
        points: FloatArray,
    ) -> None:
        self._reach = reach + 1e-6
        self._terrain = terrain
        if terrain is not None:
            # Highest collision-surface corner within reach of each cell: two 1-D max passes, linear in the
            # cells whatever reach / cell_size is (window_max clips the window to the grid).
            m = math.ceil(min(self._reach / terrain.cell_size, float(max(terrain.shape)))) + 1
            self._top = window_max(cell_maxima(terrain.surface_heights), m)
        self._boxes = boxes
        if boxes is not None:
            lo_pts = points.min(axis=0) - BIN_SIZE
            hi_pts = points.max(axis=0) + BIN_SIZE
            shape = np.ceil((hi_pts - lo_pts) / BIN_SIZE).astype(np.int64) + 1
            grid = np.zeros(tuple(shape.tolist()), dtype=bool)
            lo, hi = boxes
            i0 = np.floor((lo - self._reach - lo_pts) / BIN_SIZE).astype(np.int64)
            i1 = np.floor((hi + self._reach - lo_pts) / BIN_SIZE).astype(np.int64)
            i0 = np.maximum(i0, 0)
            i1 = np.minimum(i1, shape - 1)
            for a, b in zip(i0.tolist(), i1.tolist(), strict=True):
                if all(x <= y for x, y in zip(a, b, strict=True)):
                    grid[a[0] : b[0] + 1, a[1] : b[1] + 1, a[2] : b[2] + 1] = True
            self._origin = lo_pts
            self._grid = grid

    def near(self, centres: FloatArray) -> BoolArray:
        """(K,) bool: False only where the sphere at each (K, 3) centre surely touches nothing."""
        if self._boxes is None:
            return np.ones(centres.shape[0], dtype=bool)
        idx = np.floor((centres - self._origin) / BIN_SIZE).astype(np.int64)
        inside = np.all((idx >= 0) & (idx < np.array(self._grid.shape)), axis=1)
        near = np.zeros(centres.shape[0], dtype=bool)
        near[inside] = self._grid[idx[inside, 0], idx[inside, 1], idx[inside, 2]]
        if self._terrain is not None:
            t = self._terrain
            rows, cols = self._top.shape
            j = np.clip(np.floor((centres[:, 0] - t.origin[0]) / t.cell_size), 0, cols - 1).astype(np.int64)
            i = np.clip(np.floor((centres[:, 1] - t.origin[1]) / t.cell_size), 0, rows - 1).astype(np.int64)
            near |= centres[:, 2] - self._reach <= self._top[i, j]
        return near


def obstacle_boxes(scene_parts: list[tuple[Shape, Pose]]) -> tuple[FloatArray, FloatArray]:
    """``(lo, hi)`` (N, 3) world AABBs in metres of posed shapes (e.g. a world's towers and wire capsules)."""
    if not scene_parts:
        return np.zeros((0, 3)), np.zeros((0, 3))
    pairs = [shape_aabb(shape, pose) for shape, pose in scene_parts]
    return np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])


class HelicopterChecker:
    """Collision checks of lattice edges (sampled trajectories) against one scene.

    Args:
        scene: the world (obstacles, wires, terrain; its margin is added to ``radius``).
        points: (P, >= 3) trajectory samples of all edges (x, y, z metres first; extra columns ignored).
        offsets: (E + 1,) edge e owns ``points[offsets[e]:offsets[e + 1]]`` (at least one sample).
        radius: vehicle sphere radius, metres (> 0).
        boxes: ``(lo, hi)`` (N, 3) AABBs (metres, without margin) of every non-terrain obstacle part in
            ``scene`` (see :func:`obstacle_boxes`), enabling the prefilter of :meth:`check_many`; None
            (unknown) keeps every sample for the scene. Boxes that miss a scene obstacle give wrong answers;
            they are dropped as soon as the scene's version changes.

    Raises:
        ProblemError: malformed points/offsets or radius.
    """

    def __init__(
        self,
        scene: Scene,
        points: npt.ArrayLike,
        offsets: npt.ArrayLike,
        *,
        radius: float,
        boxes: tuple[FloatArray, FloatArray] | None = None,
    ) -> None:
        pts = np.asarray(points, dtype=np.float64)
        offs = np.asarray(offsets, dtype=np.int64)
        if pts.ndim != 2 or pts.shape[1] < 3 or not np.all(np.isfinite(pts[:, :3])):
            raise ProblemError(f"trajectory points must be a finite (P, >= 3) array, got shape {pts.shape}")
        if offs.ndim != 1 or offs.size < 1 or offs[0] != 0 or offs[-1] != pts.shape[0] or np.any(np.diff(offs) < 1):
            raise ProblemError("trajectory offsets must start at 0, end at P and give every edge >= 1 sample")
        if not (math.isfinite(radius) and radius > 0.0):
            raise ProblemError(f"vehicle radius must be finite and > 0, got {radius}")
        self._scene = scene
        self._xyz = np.ascontiguousarray(pts[:, :3])
        self._offsets = offs
        self._radius = float(radius)
        counts = np.diff(offs)
        rank = np.empty(pts.shape[0], dtype=np.int64)
        for n in np.unique(counts).tolist():
            edges = np.flatnonzero(counts == n)
            rank[(offs[edges][:, None] + np.arange(n)[None, :]).ravel()] = np.tile(bisection_rank(n), edges.size)
        self._rank = rank
        self._filter = _NearFilter(scene.terrain, boxes, self._radius + scene.margin, self._xyz)
        self._version = scene.version

    @property
    def scene(self) -> Scene:
        """The scene checked against."""
        return self._scene

    @property
    def num_edges(self) -> int:
        """E."""
        return int(self._offsets.size - 1)

    @property
    def radius(self) -> float:
        """Vehicle sphere radius in metres (without the scene margin)."""
        return self._radius

    def _edge_ids(self, edges: npt.ArrayLike) -> IntArray:
        ids = np.asarray(edges, dtype=np.int64).ravel()
        if ids.size and (ids.min() < 0 or ids.max() >= self.num_edges):
            raise ProblemError(f"edge ids must lie in [0, {self.num_edges})")
        return ids

    def check(self, edge: int) -> bool:
        """True when ``edge`` is collision-free (one sphere sweep, bisection order, early exit)."""
        e = int(self._edge_ids(np.array([edge]))[0])
        a, b = int(self._offsets[e]), int(self._offsets[e + 1])
        return bool(self._scene.sphere_sweep_free(self._xyz[a:b], self._radius))

    def check_motion(self, states: npt.ArrayLike) -> bool:
        """True when a motion off the lattice ((K, >= 3) samples, x, y, z metres first) is free."""
        xyz = np.asarray(states, dtype=np.float64)
        if xyz.ndim != 2 or xyz.shape[0] < 1 or xyz.shape[1] < 3 or not np.all(np.isfinite(xyz[:, :3])):
            raise ProblemError(f"a motion must be a finite (K, >= 3) array of samples, got shape {xyz.shape}")
        return bool(self._scene.sphere_sweep_free(np.ascontiguousarray(xyz[:, :3]), self._radius))

    def explain_motion(self, states: npt.ArrayLike) -> str:
        """What blocks a motion ((K, >= 3) samples, x, y, z m first; K = 1: one state), or "" when it is free.

        The first blocked sample's cause as a user would fix it: the terrain (below it, or within the clearance
        of it, with the ground height there), or the obstacles whose clearance it enters (each tested alone, by
        its map name); for K > 1 also where along the motion; then the sample's position. Slow by design (a test per
        obstacle): the planner asks only after a plan failed.
        """
        xyz = np.asarray(states, dtype=np.float64)[:, :3]
        blocked = self._scene.spheres_collide_mask(xyz, self._radius)
        if not blocked.any():
            return ""
        k = int(np.argmax(blocked))
        centre = xyz[k : k + 1]
        clearance = self._radius + self._scene.margin
        causes = []
        for name in self._scene.names:
            alone = self._scene.alone(name)
            if not alone.spheres_collide(centre, self._radius):
                continue
            terrain = alone.terrain
            if terrain is None:
                causes.append(f"obstacle {name[:80]!r}")
                continue
            ground = float(terrain.surface_at(centre[:, :2], interpolation="triangles")[0])
            under = bool(terrain.below(centre, interpolation="triangles")[0])
            relation = "below it" if under else f"within {clearance:g} m of it"
            causes.append(f"the terrain ({relation}, ground at {ground:.1f} m)")
        shown = ", ".join(causes[:MAX_CAUSES]) + (
            f" and {len(causes) - MAX_CAUSES} more" if len(causes) > MAX_CAUSES else ""
        )
        where = f" at sample {k + 1} of {xyz.shape[0]}" if xyz.shape[0] > 1 else ""
        x, y, z = (float(v) for v in centre[0])
        return f"{shown or 'the map'}{where} ({x:.1f}, {y:.1f}, {z:.1f} m)"

    def check_many(self, edges: npt.ArrayLike) -> BoolArray:
        """(K,) bool, True where each of the (K,) edge ids is free; same answers as :meth:`check`."""
        ids = self._edge_ids(edges)
        if ids.size == 0:
            return np.zeros(0, dtype=bool)
        unique, inverse = np.unique(ids, return_inverse=True)
        free = np.ones(unique.size, dtype=bool)
        counts = self._offsets[unique + 1] - self._offsets[unique]
        local_edge = np.repeat(np.arange(unique.size, dtype=np.int64), counts)
        starts = np.repeat(self._offsets[unique], counts)
        within = np.arange(local_edge.size, dtype=np.int64) - np.repeat(np.cumsum(counts) - counts, counts)
        point_ids = starts + within
        centres = self._xyz[point_ids]
        terrain = self._scene.terrain
        if terrain is not None:
            below = terrain.below(centres, interpolation="triangles")
            free[np.unique(local_edge[below])] = False
        if self._scene.version != self._version:  # the scene changed: the boxes may be stale, drop them
            self._filter = _NearFilter(self._scene.terrain, None, self._radius + self._scene.margin, self._xyz)
            self._version = self._scene.version
        near = self._filter.near(centres)
        rank = self._rank[point_ids]
        rank[~near] = -1
        max_rank = int(rank.max())
        low = 0
        width = 1
        while low <= max_rank:
            high = low + width
            sel = np.flatnonzero((rank >= low) & (rank < high) & free[local_edge])
            for start in range(0, sel.size, CHUNK_POINTS):
                part = sel[start : start + CHUNK_POINTS]
                part = part[free[local_edge[part]]]
                if part.size == 0:
                    continue
                hits = self._scene.spheres_collide_mask(centres[part], self._radius)
                free[np.unique(local_edge[part[hits]])] = False
            low = high
            width *= 2
        return free[inverse]


def helicopter_checker(scene: Scene, domain: object) -> HelicopterChecker:
    """The edge checker of a helicopter domain's lattice against ``scene`` (e.g. one built from messages).

    Args:
        scene: obstacles, wires and terrain in the lattice frame (metres); its margin is added.
        domain: a :class:`~drd_planner.domains.helicopter.HelicopterDomain` (anything with ``lattice`` and
            ``vehicle_radius`` attributes).
    """
    lattice = getattr(domain, "lattice", None)
    radius = getattr(domain, "vehicle_radius", None)
    if lattice is None or radius is None:
        raise ProblemError(f"helicopter_checker needs a helicopter domain, got {type(domain).__name__}")
    return HelicopterChecker(scene, lattice.points, lattice.offsets, radius=float(radius))
