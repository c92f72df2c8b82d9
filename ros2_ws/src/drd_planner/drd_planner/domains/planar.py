"""The planar (2D) domain: a random geometric graph in the unit square and seeded box-world models.

Everything here is self-contained and exact: obstacles are closed axis-aligned boxes and an edge (a
straight segment between its end vertices) is checked analytically with a vectorised slab test, so no
FCL and no occupancy grid are needed. It backs ``drd demo`` and the tests that need a problem without
external data.

World models follow the authors' 2D scripts (ALGORITHMS.md section 6.2; [CODE]
``dataset_processing/2D_dataset_creation/example_environments``):

- ``"one_wall"``: a wall of width 0.2 centred at x = 0.5 spanning the full height, with 5 slots of height 0.1
  (6 solid blocks of height 1/12 between and around them). A fixed list of up to 15 open/closed slot
  patterns with at least 2 open is drawn once per seed; each world picks one uniformly and adds a
  Poisson(8) forest of 0.1 x 0.1 squares with centres uniform in the unit square.
- ``"forest"``: 12 squares of side 0.1 whose centres come from a 5-component Gaussian mixture (means
  (0.3,0.3), (0.1,0.5), (0.7,0.7), (0.9,0.5), (0.5,0.5); covariance 0.01 I; equal weights), rejected
  outside [0.075, 0.925]^2, plus a Poisson(4) number of squares uniform in that box.
- ``"moving_wall"``: a full-height wall of width 0.15 centred at x ~ U[0.2, 0.8] with one gap of height
  0.1 whose centre is at y ~ U[0.2, 0.8].

Units: the unit square, lengths are Euclidean distances in the same unit.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.problem import Problem
from drd_planner.core.worlds import WorldDatabase
from drd_planner.data.library_builder import build_path_library, split_worlds
from drd_planner.exceptions import ProblemError

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]
IntArray = npt.NDArray[np.int64]
PointSampler = Callable[[np.random.Generator], FloatArray | None]

WORLD_MODELS: tuple[str, ...] = ("one_wall", "forest", "moving_wall")

SQUARE_SIDE = 0.1
ONE_WALL_X = 0.5
ONE_WALL_WIDTH = 0.2
ONE_WALL_SLOTS = 5
ONE_WALL_SLOT_HEIGHT = 0.1
ONE_WALL_MAX_PATTERNS = 15
ONE_WALL_FOREST_RATE = 8.0
FOREST_MEANS: FloatArray = np.array([[0.3, 0.3], [0.1, 0.5], [0.7, 0.7], [0.9, 0.5], [0.5, 0.5]])
FOREST_SIGMA = math.sqrt(0.01)
FOREST_SQUARES = 12
FOREST_RATE = 4.0
FOREST_BOX = (0.075, 0.925)
MOVING_WALL_WIDTH = 0.15
MOVING_WALL_GAP = 0.1
MOVING_WALL_X_RANGE = (0.2, 0.8)
MOVING_WALL_GAP_RANGE = (0.2, 0.8)

__all__ = [
    "WORLD_MODELS",
    "edge_free_matrix",
    "make_planar_problem",
    "one_wall_patterns",
    "random_geometric_graph",
    "rgg_radius",
    "sample_worlds",
    "segments_hit_boxes",
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


def random_geometric_graph(
    num_vertices: int, *, seed: int, eta: float = 1.0
) -> tuple[ExplicitGraph, int, int]:
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
    adjacency = coo_array(
        (np.ones(pairs.shape[0]), (pairs[:, 0], pairs[:, 1])), shape=(num_vertices, num_vertices)
    )
    _, labels = connected_components(adjacency, directed=False)
    if labels[start] != labels[goal]:
        raise ProblemError(
            f"start {start} and goal {goal} are not connected in the random geometric graph "
            f"(N={num_vertices}, eta={eta}, seed={seed}); raise num_vertices or eta"
        )
    return graph, start, goal


# --------------------------------------------------------------------------------------------------
# Exact segment / box collision


def _as_boxes(boxes: npt.ArrayLike) -> FloatArray:
    """Validate and return boxes as a (k, 4) float64 array of (xmin, ymin, xmax, ymax)."""
    b = np.asarray(boxes, dtype=np.float64)
    if b.size == 0:
        return np.zeros((0, 4), dtype=np.float64)
    if b.ndim != 2 or b.shape[1] != 4:
        raise ProblemError(f"boxes must have shape (k, 4) as (xmin, ymin, xmax, ymax), got {b.shape}")
    if not np.all(np.isfinite(b)) or np.any(b[:, 2] < b[:, 0]) or np.any(b[:, 3] < b[:, 1]):
        raise ProblemError("boxes must be finite with xmin <= xmax and ymin <= ymax")
    return b


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
    bx = _as_boxes(boxes)
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
        bx = _as_boxes(boxes)
        if bx.shape[0]:
            x[h] = ~segments_hit_boxes(p0, p1, bx).any(axis=1)
    return x


# --------------------------------------------------------------------------------------------------
# World models


def one_wall_patterns(seed: int) -> IntArray:
    """The fixed slot-pattern list of the one-wall model for a seed.

    Like the authors' script: 15 random 0/1 rows over the 5 slots (1 = open), rows with fewer than 2 open
    slots dropped (redrawn in the unlikely case that none is left), duplicates kept.

    Returns:
        (p, 5) int64 patterns, 1 <= p <= 15.
    """
    rng = np.random.default_rng(seed)
    while True:
        draws = rng.integers(0, 2, size=(ONE_WALL_MAX_PATTERNS, ONE_WALL_SLOTS), dtype=np.int64)
        patterns: IntArray = np.asarray(draws[draws.sum(axis=1) >= 2], dtype=np.int64)
        if patterns.shape[0]:
            return np.asarray(patterns, dtype=np.int64)


def _one_wall_boxes(pattern: IntArray) -> FloatArray:
    """Boxes (k, 4) of the wall with slots open where ``pattern`` is 1."""
    gap = ONE_WALL_SLOT_HEIGHT
    block = (1.0 - ONE_WALL_SLOTS * gap) / (ONE_WALL_SLOTS + 1)
    x0, x1 = ONE_WALL_X - ONE_WALL_WIDTH / 2, ONE_WALL_X + ONE_WALL_WIDTH / 2
    out = []
    for i in range(ONE_WALL_SLOTS + 1):
        y0 = i * (block + gap)
        out.append((x0, y0, x1, y0 + block))
    for i in range(ONE_WALL_SLOTS):
        if pattern[i] == 0:
            y0 = i * (block + gap) + block
            out.append((x0, y0, x1, y0 + gap))
    return np.array(out, dtype=np.float64)


def _squares(centres: FloatArray) -> FloatArray:
    """Boxes (k, 4) of side 0.1 centred at (k, 2) points."""
    h = SQUARE_SIDE / 2
    return np.concatenate([centres - h, centres + h], axis=1).reshape(-1, 4)


def _covers(centre: FloatArray, keep_clear: FloatArray) -> bool:
    """Whether the square centred at ``centre`` (2,) covers any of the (p, 2) points."""
    if keep_clear.shape[0] == 0:
        return False
    return bool(np.any(np.all(np.abs(keep_clear - centre) <= SQUARE_SIDE / 2, axis=1)))


def _draw_centres(
    rng: np.random.Generator,
    count: int,
    draw_one: PointSampler,
    keep_clear: FloatArray,
    max_tries: int = 1000,
) -> FloatArray:
    """``count`` square centres (count, 2) from ``draw_one(rng) -> (2,) | None``, redrawing covering ones."""
    out: list[FloatArray] = []
    tries = 0
    while len(out) < count and tries < max_tries * max(count, 1):
        tries += 1
        c = draw_one(rng)
        if c is None or _covers(c, keep_clear):
            continue
        out.append(c)
    return np.array(out, dtype=np.float64).reshape(-1, 2)


def _uniform_point(lo: float, hi: float) -> PointSampler:
    """A sampler of points uniform in [lo, hi]^2."""

    def draw(rng: np.random.Generator) -> FloatArray:
        return lo + (hi - lo) * rng.random(2)

    return draw


def _mixture_point(rng: np.random.Generator) -> FloatArray | None:
    """A point of the forest's Gaussian mixture, or None when it falls outside the forest box."""
    mean = FOREST_MEANS[rng.integers(FOREST_MEANS.shape[0])]
    c = mean + FOREST_SIGMA * rng.standard_normal(2)
    lo, hi = FOREST_BOX
    if np.any(c < lo) or np.any(c > hi):
        return None
    return np.asarray(c, dtype=np.float64)


def sample_worlds(
    model: str, n: int, *, seed: int, keep_clear: npt.ArrayLike | None = None
) -> list[FloatArray]:
    """Sample n box worlds from a world model.

    Args:
        model: one of :data:`WORLD_MODELS` ("one_wall", "forest", "moving_wall").
        n: number of worlds.
        seed: seed of ``numpy.random.default_rng`` (same seed, same worlds).
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
    clear = (
        np.zeros((0, 2)) if keep_clear is None else np.asarray(keep_clear, dtype=np.float64).reshape(-1, 2)
    )
    rng = np.random.default_rng(seed)
    worlds: list[FloatArray] = []
    if model == "one_wall":
        patterns = one_wall_patterns(int(rng.integers(2**32)))
        walls = [_one_wall_boxes(p) for p in patterns]
        uniform = _uniform_point(0.0, 1.0)
        for _ in range(n):
            wall = walls[int(rng.integers(len(walls)))]
            squares = _squares(_draw_centres(rng, int(rng.poisson(ONE_WALL_FOREST_RATE)), uniform, clear))
            worlds.append(np.concatenate([wall, squares], axis=0))
    elif model == "forest":
        uniform = _uniform_point(*FOREST_BOX)
        for _ in range(n):
            mixture = _draw_centres(rng, FOREST_SQUARES, _mixture_point, clear)
            extra = _draw_centres(rng, int(rng.poisson(FOREST_RATE)), uniform, clear)
            worlds.append(_squares(np.concatenate([mixture, extra], axis=0)))
    else:  # moving_wall
        for _ in range(n):
            x = rng.uniform(*MOVING_WALL_X_RANGE)
            y = rng.uniform(*MOVING_WALL_GAP_RANGE)
            x0, x1 = x - MOVING_WALL_WIDTH / 2, x + MOVING_WALL_WIDTH / 2
            g0, g1 = y - MOVING_WALL_GAP / 2, y + MOVING_WALL_GAP / 2
            worlds.append(np.array([[x0, 0.0, x1, g0], [x0, g1, x1, 1.0]], dtype=np.float64))
    return worlds


# --------------------------------------------------------------------------------------------------
# Problem


def make_planar_problem(
    *,
    num_vertices: int = 100,
    model: str = "one_wall",
    num_worlds: int = 300,
    max_paths: int = 100,
    seed: int = 0,
    test_fraction: float = 0.1,
    eta: float = 1.0,
    k: int = 5,
) -> Problem:
    """A complete self-generated planar problem (graph, worlds, X, library, R, split), unit check costs.

    The graph comes from :func:`random_geometric_graph` with ``seed``; the worlds, the library subsample and
    the split use seeds derived from ``seed`` (recorded in the metadata), so the same arguments always give
    identical arrays. Random squares are kept off the start and goal vertices.

    Args:
        num_vertices: RGG vertex count N.
        model: world model (see :data:`WORLD_MODELS`).
        num_worlds: n sampled worlds.
        max_paths: library size cap m.
        seed: master seed.
        test_fraction: share of worlds held out (drawn among worlds with a valid library path).
        eta: RGG radius multiplier.
        k: Yen's k per world.

    Raises:
        ProblemError: bad arguments, start/goal disconnected, or no world has a start-goal path.
    """
    graph, start, goal = random_geometric_graph(num_vertices, seed=seed, eta=eta)
    world_seed, library_seed, split_seed = (int(s) for s in np.random.SeedSequence(seed).generate_state(3))
    states = graph.vertex_states
    assert states is not None
    keep_clear = states[[start, goal]]
    boxes = sample_worlds(model, num_worlds, seed=world_seed, keep_clear=keep_clear)
    x = edge_free_matrix(graph, boxes)
    library = build_path_library(graph, x, start, goal, k=k, max_paths=max_paths, seed=library_seed)
    r = library.valid_paths(x)
    train, test = split_worlds(r, test_fraction=test_fraction, seed=split_seed)
    metadata: dict[str, Any] = {
        "domain": "planar",
        "world_model": model,
        "seed": seed,
        "num_vertices": num_vertices,
        "eta": eta,
        "radius": rgg_radius(num_vertices, eta=eta),
        "num_worlds": num_worlds,
        "k": k,
        "max_paths": max_paths,
        "test_fraction": test_fraction,
        "world_seed": world_seed,
        "library_seed": library_seed,
        "split_seed": split_seed,
        "keep_clear": keep_clear.tolist(),
        "solvable_worlds": int(r.any(axis=1).sum()),
    }
    return Problem(
        name=f"planar_{model}_N{num_vertices}_seed{seed}",
        library=library,
        edge_costs=np.ones(graph.num_edges),
        graph=graph,
        start=start,
        goal=goal,
        worlds=WorldDatabase(x, r, train, test),
        metadata=metadata,
    )
