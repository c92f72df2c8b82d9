"""The planar (2D) domain: a random geometric graph in the unit square and seeded box worlds.

Everything here is self-contained and exact: obstacles are closed axis-aligned boxes and an edge (a
straight segment between its end vertices) is checked analytically with a vectorised slab test, so no
FCL and no occupancy grid are needed. Every one of the seven world models (one_wall, two_wall, forest,
moving_wall, baffle, maze, bugtrap; :mod:`drd_planner.domains.planar_worlds`; docs/algorithms.md)
is a union of axis-aligned rectangles, so boxes represent them without approximation.

:class:`PlanarDomain` is the :class:`drd_planner.domains.base.Domain` of the dataset builder;
:func:`drd_planner.data.planar_problem.make_planar_problem` builds a complete small problem for ``drd demo``
and the tests.

Units: the unit square; lengths are Euclidean distances in the same unit.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
import numpy.typing as npt
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.domains.online import OnlineDefaults
from drd_planner.domains.params import SpecParams
from drd_planner.domains.planar_worlds import (
    PLANAR_VARIANT,
    WORLD_MODELS,
    as_boxes,
    generate_world,
    one_wall_patterns,
    world_from_rng,
)
from drd_planner.exceptions import ProblemError

_CHUNK_ELEMENTS = 1 << 20  # segment x box pairs per vectorised block

__all__ = [
    "WORLD_MODELS",
    "PlanarChecker",
    "PlanarDomain",
    "edge_free_matrix",
    "one_wall_patterns",
    "random_geometric_graph",
    "rgg_radius",
    "sample_worlds",
    "segments_hit_boxes",
    "validate_edge_ids",
]


# --------------------------------------------------------------------------------------------------
# Graph


def rgg_radius(num_vertices: int, *, eta: float = 1.0) -> float:
    """Connection radius r = 2 eta sqrt(1.5) sqrt(area / pi) sqrt(log N / N) of the RGG, area = 1.

    ([CODE] ``rgg.m``; with eta = 1, N = 100 gives r = 0.2966 as in the released ``dataset_2d_1``.)
    """
    if num_vertices < 2:
        raise ProblemError(f"a random geometric graph needs at least 2 vertices, got {num_vertices}")
    if not eta > 0:
        raise ProblemError(f"eta must be positive, got {eta}")
    n = float(num_vertices)
    return 2.0 * eta * math.sqrt(1.5) * math.sqrt(1.0 / math.pi) * math.sqrt(math.log(n) / n)


def random_geometric_graph(num_vertices: int, *, seed: int, eta: float = 1.0) -> tuple[ExplicitGraph, int, int]:
    """A random geometric graph on N uniform points in the unit square.

    Args:
        num_vertices: N.
        seed: seed of ``numpy.random.default_rng`` for the points.
        eta: radius multiplier (see :func:`rgg_radius`).

    Returns:
        ``(graph, start, goal)``: an undirected graph whose edges ``[u, v]`` (u < v, sorted) join the point
        pairs at distance <= r, with Euclidean lengths and ``vertex_states`` the (N, 2) coordinates; start is
        the vertex nearest (0, 0), goal the vertex nearest (1, 1).

    Raises:
        ProblemError: N < 2, start = goal, or start and goal are not connected.
    """
    radius = rgg_radius(num_vertices, eta=eta)
    rng = np.random.default_rng(seed)
    points = rng.random((num_vertices, 2))
    pairs = cKDTree(points).query_pairs(radius, output_type="ndarray").astype(np.int64)
    pairs = np.sort(pairs, axis=1)
    pairs = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
    lengths = np.linalg.norm(points[pairs[:, 1]] - points[pairs[:, 0]], axis=1)
    graph = ExplicitGraph(pairs, lengths, num_vertices, directed=False, vertex_states=points)
    start = int(np.argmin(np.linalg.norm(points, axis=1)))
    goal = int(np.argmin(np.linalg.norm(points - 1.0, axis=1)))
    if start == goal:
        raise ProblemError("start and goal are the same vertex; use more vertices")
    adjacency = coo_array((np.ones(pairs.shape[0]), (pairs[:, 0], pairs[:, 1])), shape=(num_vertices, num_vertices))
    _, labels = connected_components(adjacency, directed=False)
    if labels[start] != labels[goal]:
        raise ProblemError(
            f"start {start} and goal {goal} are not connected in the random geometric graph "
            f"(N={num_vertices}, eta={eta}, seed={seed}); raise num_vertices or eta"
        )
    return graph, start, goal


# --------------------------------------------------------------------------------------------------
# Exact segment / box collision


def segments_hit_boxes(p0: npt.ArrayLike, p1: npt.ArrayLike, boxes: npt.ArrayLike) -> BoolArray:
    """Exact intersection of segments with closed axis-aligned boxes (slab test).

    A segment touching a box (a corner or a side) counts as a hit; a degenerate segment (p0 = p1) is a
    point-in-box test. No sampling: the answer is exact up to floating-point rounding.

    Args:
        p0: (S, 2) segment start points.
        p1: (S, 2) segment end points.
        boxes: (k, 4) boxes (xmin, ymin, xmax, ymax).

    Returns:
        (S, k) bool, True where segment s intersects box j.
    """
    a = np.asarray(p0, dtype=np.float64).reshape(-1, 2)
    b = np.asarray(p1, dtype=np.float64).reshape(-1, 2)
    if a.shape != b.shape:
        raise ProblemError(f"segment start and end arrays differ in shape: {a.shape} vs {b.shape}")
    bx = as_boxes(boxes)
    d = b - a
    t_enter = np.zeros((a.shape[0], bx.shape[0]))
    t_exit = np.ones((a.shape[0], bx.shape[0]))
    with np.errstate(divide="ignore", invalid="ignore"):
        for axis in (0, 1):
            p = a[:, axis, None]
            da = d[:, axis, None]
            lo = bx[None, :, axis]
            hi = bx[None, :, axis + 2]
            t1 = (lo - p) / da
            t2 = (hi - p) / da
            near = np.minimum(t1, t2)
            far = np.maximum(t1, t2)
            parallel = da == 0.0
            inside = (p >= lo) & (p <= hi)
            near = np.where(parallel, np.where(inside, -np.inf, np.inf), near)
            far = np.where(parallel, np.where(inside, np.inf, -np.inf), far)
            t_enter = np.maximum(t_enter, near)
            t_exit = np.minimum(t_exit, far)
    return np.asarray(t_enter <= t_exit, dtype=bool)


def edge_free_matrix(graph: ExplicitGraph, boxes_per_world: Sequence[npt.ArrayLike]) -> BoolArray:
    """X for box worlds: edge e is free in world h iff its segment meets none of the world's boxes.

    The segment test covers the endpoints, so a free edge has both end vertices outside every box.

    Args:
        graph: a graph with (V, 2) ``vertex_states`` (x, y) in the unit square.
        boxes_per_world: n arrays (k_h, 4) of closed boxes (xmin, ymin, xmax, ymax); k_h may be 0.

    Returns:
        (n, E) bool, True where the edge is collision-free.
    """
    states = graph.vertex_states
    if states is None or states.shape[1] != 2:
        raise ProblemError("edge_free_matrix needs a graph with (V, 2) vertex coordinates")
    p0 = states[graph.edges[:, 0]]
    p1 = states[graph.edges[:, 1]]
    x = np.ones((len(boxes_per_world), graph.num_edges), dtype=bool)
    for h, boxes in enumerate(boxes_per_world):
        bx = as_boxes(boxes)
        if bx.shape[0]:
            x[h] = ~segments_hit_boxes(p0, p1, bx).any(axis=1)
    return x


# --------------------------------------------------------------------------------------------------
# World models (defined in planar_worlds)


def sample_worlds(model: str, n: int, *, seed: int, keep_clear: npt.ArrayLike | None = None) -> list[FloatArray]:
    """Sample n planar box worlds from a world model.

    World i is drawn from the i-th child of ``numpy.random.SeedSequence(seed)``; the slot-pattern lists of the
    wall models come from ``seed`` itself.

    Args:
        model: one of :data:`WORLD_MODELS`.
        n: number of worlds.
        seed: master seed (same seed, same worlds; a longer list extends a shorter one).
        keep_clear: optional (p, 2) points (for example the start and goal vertices) that no random square
            may cover; a covering square is redrawn. Walls are not moved.

    Returns:
        n arrays (k_h, 4) of boxes (xmin, ymin, xmax, ymax) in the unit square's units.

    Raises:
        ProblemError: unknown model or negative n.
    """
    if model not in WORLD_MODELS:
        raise ProblemError(f"unknown planar world model {model!r}; choose one of {', '.join(WORLD_MODELS)}")
    if n < 0:
        raise ProblemError(f"number of worlds must be non-negative, got {n}")
    children = np.random.SeedSequence(seed).spawn(n)
    return [world_from_rng(model, np.random.default_rng(c), pattern_seed=seed, keep_clear=keep_clear) for c in children]


# --------------------------------------------------------------------------------------------------
# Domain


def validate_edge_ids(edges: npt.ArrayLike, num_edges: int) -> IntArray:
    """Edge ids as a (K,) int64 array.

    Raises:
        ProblemError: non-integer ids or ids outside [0, num_edges).
    """
    arr = np.asarray(edges)
    if arr.size == 0:
        return np.zeros(0, dtype=np.int64)
    if arr.dtype == np.bool_ or not np.issubdtype(arr.dtype, np.integer):
        raise ProblemError(f"edge ids must be integers, got dtype {arr.dtype}")
    ids = arr.astype(np.int64).ravel()
    if ids.min() < 0 or ids.max() >= num_edges:
        raise ProblemError(f"edge ids must lie in [0, {num_edges}), got range [{ids.min()}, {ids.max()}]")
    return ids


class PlanarChecker:
    """Exact edge checker of one box world: an edge is free iff its straight segment meets no box.

    The segment test includes both end vertices, so a free edge also has free endpoints.
    """

    def __init__(self, graph: ExplicitGraph, boxes: npt.ArrayLike) -> None:
        """Check the edges of ``graph`` ((V, 2) vertex coordinates) against (k, 4) closed boxes."""
        states = graph.vertex_states
        if states is None or states.shape[1] != 2:
            raise ProblemError("a planar checker needs a graph with (V, 2) vertex coordinates")
        self._p0 = states[graph.edges[:, 0]]
        self._p1 = states[graph.edges[:, 1]]
        self._boxes = as_boxes(boxes)
        self._num_edges = graph.num_edges

    @property
    def boxes(self) -> FloatArray:
        """(k, 4) boxes of the world."""
        return self._boxes

    def check(self, edge: int) -> bool:
        """True when edge ``edge`` is collision-free."""
        return bool(self.check_many(np.array([edge]))[0])

    def check_motion(self, states: npt.ArrayLike) -> bool:
        """True when the polyline through the (K, 2) states (a motion off the graph) meets no box."""
        pts = np.asarray(states, dtype=np.float64).reshape(-1, 2)
        if self._boxes.shape[0] == 0:
            return True
        if pts.shape[0] == 1:
            pts = np.vstack([pts, pts])
        return not bool(segments_hit_boxes(pts[:-1], pts[1:], self._boxes).any())

    def check_many(self, edges: npt.ArrayLike) -> BoolArray:
        """(K,) bool, True where each of the (K,) edge ids is collision-free."""
        ids = validate_edge_ids(edges, self._num_edges)
        free = np.ones(ids.size, dtype=bool)
        k = self._boxes.shape[0]
        if k == 0 or ids.size == 0:
            return free
        rows = max(1, _CHUNK_ELEMENTS // k)
        for lo in range(0, ids.size, rows):
            chunk = ids[lo : lo + rows]
            hits = segments_hit_boxes(self._p0[chunk], self._p1[chunk], self._boxes)
            free[lo : lo + rows] = ~hits.any(axis=1)
        return free


def _int_field(name: str, value: object, minimum: int) -> int:
    """``value`` as an int >= minimum, or a ProblemError naming the field."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum:
        raise ProblemError(f"planar domain: {name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


@dataclass(frozen=True)
class PlanarDomain(SpecParams, OnlineDefaults):
    """The planar domain: a seeded random geometric graph in the unit square and box worlds.

    Graph: :func:`random_geometric_graph` (``num_vertices`` points, radius :func:`rgg_radius` with ``eta``,
    start nearest (0, 0), goal nearest (1, 1)). Worlds: the seven models of
    :mod:`drd_planner.domains.planar_worlds` (planar parameters). Edges: straight segments, checked exactly.

    Attributes:
        num_vertices: N, the number of random points (count); 100, 150 or 200 in the authors' datasets.
        seed: seed of the graph's points (seed).
        eta: connection radius multiplier (ratio); 1 in the authors' datasets.
        pattern_seed: seed of the fixed slot-pattern lists shared by all worlds of ``one_wall`` / ``two_wall``
            (seed).
        keep_clear: keep random squares off the start and goal vertices (flag); the authors did not.
    """

    SPEC_LABEL: ClassVar[str] = "planar"

    num_vertices: int = 100
    seed: int = 0
    eta: float = 1.0
    pattern_seed: int = 0
    keep_clear: bool = False
    _built: tuple[ExplicitGraph, int, int] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "num_vertices", _int_field("num_vertices", self.num_vertices, 2))
        object.__setattr__(self, "seed", _int_field("seed", self.seed, 0))
        object.__setattr__(self, "pattern_seed", _int_field("pattern_seed", self.pattern_seed, 0))
        if isinstance(self.eta, bool) or not isinstance(self.eta, int | float) or not math.isfinite(self.eta):
            raise ProblemError(f"planar domain: eta must be a finite number, got {self.eta!r}")
        object.__setattr__(self, "eta", float(self.eta))
        if not isinstance(self.keep_clear, bool):
            raise ProblemError(f"planar domain: keep_clear must be true or false, got {self.keep_clear!r}")
        built = random_geometric_graph(self.num_vertices, seed=self.seed, eta=self.eta)
        object.__setattr__(self, "_built", built)

    def spec(self) -> dict[str, Any]:
        """JSON-able parameters (tuples as lists); ``PlanarDomain.from_spec(d.spec()) == d``."""
        return self.to_spec()

    @property
    def name(self) -> str:
        """``"planar"``."""
        return "planar"

    @property
    def state_columns(self) -> str:
        """A point of the unit square."""
        return "x, y (unit square)"

    @property
    def graph(self) -> ExplicitGraph:
        """The undirected random geometric graph; ``vertex_states`` (V, 2) are (x, y)."""
        return self._built[0]

    @property
    def start(self) -> int:
        """The vertex nearest (0, 0)."""
        return self._built[1]

    @property
    def goal(self) -> int:
        """The vertex nearest (1, 1)."""
        return self._built[2]

    @property
    def world_models(self) -> tuple[str, ...]:
        """All seven planar world models."""
        return WORLD_MODELS

    def keep_clear_points(self) -> FloatArray | None:
        """(2, 2) start and goal coordinates when ``keep_clear`` is set, else None."""
        if not self.keep_clear:
            return None
        states = self.graph.vertex_states
        assert states is not None
        return np.asarray(states[[self.start, self.goal]], dtype=np.float64)

    def make_world(self, model: str, seed: int) -> FloatArray:
        """The (k, 4) boxes of ``model`` drawn with ``seed`` (see :func:`planar_worlds.generate_world`)."""
        return generate_world(
            model,
            seed=seed,
            variant=PLANAR_VARIANT,
            pattern_seed=self.pattern_seed,
            keep_clear=self.keep_clear_points(),
        )

    def checker(self, world: npt.ArrayLike) -> PlanarChecker:
        """An exact checker of this graph's edges against the (k, 4) boxes ``world``."""
        return PlanarChecker(self.graph, world)

    def edge_trajectories(self) -> None:
        """None: planar edges are straight segments between their end vertices."""
        return None

    def check_metadata(self) -> dict[str, Any]:
        """How edges are checked (exact segment / closed-box intersection, point robot, no margin)."""
        return {
            "method": "exact straight segment vs closed axis-aligned boxes (slab test), endpoints included",
            "vehicle": "point",
            "margin": 0.0,
            "length_unit": "unit square (dimensionless)",
            "world_variant": PLANAR_VARIANT.name,
            "pattern_seed": self.pattern_seed,
            "keep_clear": self.keep_clear,
        }
