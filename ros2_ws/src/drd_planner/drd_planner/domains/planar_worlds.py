"""Seeded generative world models of the planar and SE(2) domains, as axis-aligned boxes.

Every model of docs/algorithms.md, "The planar world models", is built from closed axis-aligned rectangles
``(xmin, ymin, xmax, ymax)`` in the unit square (lengths are in the same unitless scale), so a world is
a (k, 4) float64 array and collision checks stay exact (segments, planar domain) or cheap (waypoints,
SE(2) domain). Parameters follow the spec; where it is vague the choice made here is stated below and
was checked against the released thumbnails / invalid-edge renderings of the authors' data.

- ``one_wall``: a full-height wall of width 0.2 centred at x = 0.5 with 5 slots of height 0.1 (6 solid
  blocks of height 1/12 around them; the thumbnails of ``dataset_2d_1`` measure 0.083 / 0.098). A fixed
  list of up to 15 open/closed slot patterns (at least 2 open) is drawn from ``pattern_seed``; each world
  picks one uniformly and adds a Poisson(8) number of 0.1 x 0.1 squares, centres uniform in the unit
  square (planar) or in [0.2, 0.8] x [0.1, 0.9] (SE(2)).
- ``two_wall``: two such walls of width 0.15 centred at x = 0.3 and x = 0.7 (same slot layout); a fixed
  list of up to 20 joint 10-slot patterns with at least 2 open slots in each wall; Poisson(3) squares.
- ``forest``: 12 squares of side 0.1 from a Gaussian mixture, rejected outside [0.075, 0.925]^2, plus a
  Poisson(4) number of squares uniform in that box. Planar: 5 components at (0.3,0.3), (0.1,0.5),
  (0.7,0.7), (0.9,0.5), (0.5,0.5) with covariance 0.01 I. SE(2): 4 components at (0.3,0.3), (0.3,0.7),
  (0.7,0.3), (0.7,0.7) with covariance 0.005 I (the spec gives only their number and variance).
- ``moving_wall``: a full-height wall of width 0.15 centred at x ~ U[0.2, 0.8] with one gap of height 0.1
  centred at y ~ U[0.2, 0.8].
- ``baffle``: centre (cx, cy) ~ U([0.3, 0.7] x [0.2, 0.8]); a left slab [cx-0.15, cx-0.05] x [0, cy+0.075]
  rising from the bottom and a right slab [cx+0.05, cx+0.15] x [cy-0.075, 1] hanging from the top (width
  0.1 each): a 0.1-wide passage between them in which the slabs overlap vertically by 0.15.
- ``maze``: five columns of width 0.2; between them vertical walls (width 0.02, centred at x = 0.2, 0.4,
  0.6, 0.8) spanning the full height except one gap of height 0.1 ("clearance") whose lower edge is
  ~U[0, 0.9], independently per wall (the authors' ``randfixedsum`` couples the displacements; the
  coupling is not specified and not reproduced). Column j holds the tunnel segment from the lowest to the
  highest edge of the gaps on its two sides (column 0 from y = 0, column 4 up to y = 1); a horizontal wall
  (thickness 0.02) closes it below and above across the column. The result is one left-right tunnel
  from the corner (0, 0) to the corner (1, 1), as in the ``dataset_2d_5`` thumbnails.
- ``bugtrap``: a U of wall thickness 0.05 whose outer size is 0.6 across (inner back 0.5) and 0.35 deep,
  bounding-box centre ~U([0.3, 0.7] x [0.2, 0.8]). "vertical": back on the right, opening towards -x;
  "horizontal": back on top, opening towards -y (both open towards the start corner, as in the
  ``dataset_2d_7`` thumbnails). Planar: orientation uniform among both and no squares. (The spec says the
  2D script adds Poisson(8) squares of side 0.1, but the released ``dataset_2d_7`` has none: none in its
  thumbnail, none in renderings of its invalid edges, every world solvable, and 0.80 of its edges free,
  which the trap alone reproduces (0.80) while Poisson(8) squares would give 0.64.) SE(2): vertical
  only, plus Poisson(6) squares of side 0.05, uniform in the unit square.

Every random square may optionally be kept off given points (``keep_clear``, for example the start and
goal): a square covering one is redrawn. Walls are never moved. Boxes may stick out of the unit square.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.exceptions import ProblemError

PointSampler = Callable[[np.random.Generator], FloatArray | None]
Rect = tuple[float, float, float, float]

__all__ = [
    "PLANAR_VARIANT",
    "SE2_VARIANT",
    "VARIANTS",
    "WORLD_MODELS",
    "WorldVariant",
    "as_boxes",
    "generate_world",
    "one_wall_patterns",
    "two_wall_patterns",
    "wall_patterns",
    "world_from_rng",
]

WORLD_MODELS: tuple[str, ...] = ("one_wall", "two_wall", "forest", "moving_wall", "baffle", "maze", "bugtrap")

SQUARE_SIDE = 0.1
UNIT_BOX: Rect = (0.0, 0.0, 1.0, 1.0)

WALL_SLOTS = 5
WALL_SLOT_HEIGHT = 0.1
ONE_WALL_X = 0.5
ONE_WALL_WIDTH = 0.2
ONE_WALL_MAX_PATTERNS = 15
ONE_WALL_SQUARE_RATE = 8.0
TWO_WALL_XS = (0.3, 0.7)
TWO_WALL_WIDTH = 0.15
TWO_WALL_MAX_PATTERNS = 20
TWO_WALL_SQUARE_RATE = 3.0
MIN_OPEN_SLOTS = 2

FOREST_SQUARES = 12
FOREST_RATE = 4.0
FOREST_BOX = (0.075, 0.925)

MOVING_WALL_WIDTH = 0.15
MOVING_WALL_GAP = 0.1
MOVING_WALL_X_RANGE = (0.2, 0.8)
MOVING_WALL_GAP_RANGE = (0.2, 0.8)

BAFFLE_WIDTH = 0.1
BAFFLE_PASSAGE = 0.1
BAFFLE_OVERLAP = 0.15
BAFFLE_X_RANGE = (0.3, 0.7)
BAFFLE_Y_RANGE = (0.2, 0.8)

MAZE_COLUMNS = 5
MAZE_WALL = 0.02
MAZE_GAP = 0.1

BUGTRAP_WALL = 0.05
BUGTRAP_ACROSS = 0.6
BUGTRAP_DEPTH = 0.35
BUGTRAP_X_RANGE = (0.3, 0.7)
BUGTRAP_Y_RANGE = (0.2, 0.8)


@dataclass(frozen=True)
class WorldVariant:
    """The parameters in which the SE(2) world models differ from the planar ones.

    See docs/algorithms.md, "The planar world models".

    Attributes:
        name: ``"planar"`` or ``"se2"``.
        one_wall_square_box: (xmin, ymin, xmax, ymax) of the one-wall model's random square centres.
        forest_means: (c, 2) Gaussian-mixture component means of the forest model.
        forest_variance: per-axis variance of every component (isotropic covariance).
        bugtrap_orientations: the orientations drawn uniformly (``"vertical"``, ``"horizontal"``).
        bugtrap_square_rate: Poisson rate of the bugtrap's random squares.
        bugtrap_square_side: side of those squares.
    """

    name: str
    one_wall_square_box: Rect
    forest_means: tuple[tuple[float, float], ...]
    forest_variance: float
    bugtrap_orientations: tuple[str, ...]
    bugtrap_square_rate: float
    bugtrap_square_side: float


PLANAR_VARIANT = WorldVariant(
    name="planar",
    one_wall_square_box=UNIT_BOX,
    forest_means=((0.3, 0.3), (0.1, 0.5), (0.7, 0.7), (0.9, 0.5), (0.5, 0.5)),
    forest_variance=0.01,
    bugtrap_orientations=("vertical", "horizontal"),
    bugtrap_square_rate=0.0,
    bugtrap_square_side=0.1,
)

SE2_VARIANT = WorldVariant(
    name="se2",
    one_wall_square_box=(0.2, 0.1, 0.8, 0.9),
    forest_means=((0.3, 0.3), (0.3, 0.7), (0.7, 0.3), (0.7, 0.7)),
    forest_variance=0.005,
    bugtrap_orientations=("vertical",),
    bugtrap_square_rate=6.0,
    bugtrap_square_side=0.05,
)

#: Variant name -> parameters.
VARIANTS: Mapping[str, WorldVariant] = {"planar": PLANAR_VARIANT, "se2": SE2_VARIANT}


# --------------------------------------------------------------------------------------------------
# Boxes


def as_boxes(boxes: npt.ArrayLike) -> FloatArray:
    """Validate boxes and return them as a (k, 4) float64 array of (xmin, ymin, xmax, ymax).

    Raises:
        ProblemError: wrong shape, non-finite values, or xmax < xmin / ymax < ymin.
    """
    b = np.asarray(boxes, dtype=np.float64)
    if b.size == 0:
        return np.zeros((0, 4), dtype=np.float64)
    if b.ndim != 2 or b.shape[1] != 4:
        raise ProblemError(f"boxes must have shape (k, 4) as (xmin, ymin, xmax, ymax), got {b.shape}")
    if not np.all(np.isfinite(b)) or np.any(b[:, 2] < b[:, 0]) or np.any(b[:, 3] < b[:, 1]):
        raise ProblemError("boxes must be finite with xmin <= xmax and ymin <= ymax")
    return b


def _boxes(rects: list[Rect]) -> FloatArray:
    """(k, 4) array of rectangles, dropping empty ones (zero height or width)."""
    kept = [r for r in rects if r[2] > r[0] and r[3] > r[1]]
    return np.array(kept, dtype=np.float64).reshape(-1, 4)


def _squares(centres: FloatArray, side: float) -> FloatArray:
    """Boxes (k, 4) of the given side centred at (k, 2) points."""
    h = side / 2
    return np.concatenate([centres - h, centres + h], axis=1).reshape(-1, 4)


def _covers(centre: FloatArray, side: float, keep_clear: FloatArray) -> bool:
    """Whether the square of ``side`` centred at ``centre`` (2,) covers any of the (p, 2) points."""
    if keep_clear.shape[0] == 0:
        return False
    return bool(np.any(np.all(np.abs(keep_clear - centre) <= side / 2, axis=1)))


def _draw_squares(
    rng: np.random.Generator,
    count: int,
    draw_one: PointSampler,
    keep_clear: FloatArray,
    side: float = SQUARE_SIDE,
    max_tries: int = 1000,
) -> FloatArray:
    """``count`` squares (count, 4) with centres from ``draw_one(rng) -> (2,) | None``.

    A draw that returns None (rejected) or covers a ``keep_clear`` point is redrawn, at most
    ``max_tries * count`` draws in all (fewer squares come back if they run out).
    """
    out: list[FloatArray] = []
    tries = 0
    while len(out) < count and tries < max_tries * max(count, 1):
        tries += 1
        c = draw_one(rng)
        if c is None or _covers(c, side, keep_clear):
            continue
        out.append(c)
    return _squares(np.array(out, dtype=np.float64).reshape(-1, 2), side)


def _uniform_in(box: Rect) -> PointSampler:
    """A sampler of points uniform in the rectangle ``box``."""
    lo = np.array(box[:2])
    span = np.array(box[2:]) - lo

    def draw(rng: np.random.Generator) -> FloatArray:
        return np.asarray(lo + span * rng.random(2), dtype=np.float64)

    return draw


def _mixture_in(means: FloatArray, sigma: float, lo: float, hi: float) -> PointSampler:
    """A sampler of an equal-weight isotropic Gaussian mixture; None outside [lo, hi]^2."""

    def draw(rng: np.random.Generator) -> FloatArray | None:
        mean = means[rng.integers(means.shape[0])]
        c = mean + sigma * rng.standard_normal(2)
        if np.any(c < lo) or np.any(c > hi):
            return None
        return np.asarray(c, dtype=np.float64)

    return draw


# --------------------------------------------------------------------------------------------------
# Slot patterns of the wall models


def wall_patterns(*, seed: int, walls: int, max_patterns: int, min_open: int = MIN_OPEN_SLOTS) -> IntArray:
    """A fixed list of open/closed slot patterns for ``walls`` walls of 5 slots each.

    ``max_patterns`` random 0/1 rows (1 = open) are drawn with ``numpy.random.default_rng(seed)``; rows with
    fewer than ``min_open`` open slots in some wall are dropped (all redrawn in the unlikely case none is
    left); duplicates are kept, so frequent patterns weigh more, as in the authors' scripts.

    Returns:
        (p, 5 * walls) int64 patterns, 1 <= p <= max_patterns; columns [5w, 5w + 5) belong to wall w and
        slot 0 is the lowest.
    """
    if walls < 1 or max_patterns < 1 or not 0 <= min_open <= WALL_SLOTS:
        raise ProblemError(f"bad pattern request: walls={walls}, max_patterns={max_patterns}, min_open={min_open}")
    rng = np.random.default_rng(seed)
    while True:
        draws = rng.integers(0, 2, size=(max_patterns, WALL_SLOTS * walls), dtype=np.int64)
        per_wall = draws.reshape(max_patterns, walls, WALL_SLOTS).sum(axis=2)
        patterns = draws[(per_wall >= min_open).all(axis=1)]
        if patterns.shape[0]:
            return np.asarray(patterns, dtype=np.int64)


def one_wall_patterns(seed: int) -> IntArray:
    """The one-wall model's pattern list for a seed: (p, 5) int64, p <= 15, at least 2 open slots each."""
    return wall_patterns(seed=seed, walls=1, max_patterns=ONE_WALL_MAX_PATTERNS)


def two_wall_patterns(seed: int) -> IntArray:
    """The two-wall model's joint pattern list: (p, 10) int64, p <= 20, at least 2 open slots per wall."""
    return wall_patterns(seed=seed, walls=2, max_patterns=TWO_WALL_MAX_PATTERNS)


def _slotted_wall(x: float, width: float, pattern: IntArray) -> list[Rect]:
    """Rectangles of a full-height wall centred at ``x`` with 5 slots, open where ``pattern`` (5,) is 1."""
    gap = WALL_SLOT_HEIGHT
    block = (1.0 - WALL_SLOTS * gap) / (WALL_SLOTS + 1)
    x0, x1 = x - width / 2, x + width / 2
    out: list[Rect] = []
    for i in range(WALL_SLOTS + 1):
        y0 = i * (block + gap)
        out.append((x0, y0, x1, y0 + block))
    for i in range(WALL_SLOTS):
        if pattern[i] == 0:
            y0 = i * (block + gap) + block
            out.append((x0, y0, x1, y0 + gap))
    return out


# --------------------------------------------------------------------------------------------------
# The models


@dataclass(frozen=True)
class _Context:
    """What a model generator needs besides the world's random stream."""

    variant: WorldVariant
    pattern_seed: int
    keep_clear: FloatArray


def _one_wall(rng: np.random.Generator, ctx: _Context) -> FloatArray:
    patterns = one_wall_patterns(ctx.pattern_seed)
    wall = _boxes(_slotted_wall(ONE_WALL_X, ONE_WALL_WIDTH, patterns[int(rng.integers(patterns.shape[0]))]))
    count = int(rng.poisson(ONE_WALL_SQUARE_RATE))
    squares = _draw_squares(rng, count, _uniform_in(ctx.variant.one_wall_square_box), ctx.keep_clear)
    return np.concatenate([wall, squares], axis=0)


def _two_wall(rng: np.random.Generator, ctx: _Context) -> FloatArray:
    patterns = two_wall_patterns(ctx.pattern_seed)
    pattern = patterns[int(rng.integers(patterns.shape[0]))]
    rects: list[Rect] = []
    for w, x in enumerate(TWO_WALL_XS):
        rects += _slotted_wall(x, TWO_WALL_WIDTH, pattern[w * WALL_SLOTS : (w + 1) * WALL_SLOTS])
    squares = _draw_squares(rng, int(rng.poisson(TWO_WALL_SQUARE_RATE)), _uniform_in(UNIT_BOX), ctx.keep_clear)
    return np.concatenate([_boxes(rects), squares], axis=0)


def _forest(rng: np.random.Generator, ctx: _Context) -> FloatArray:
    lo, hi = FOREST_BOX
    means = np.array(ctx.variant.forest_means, dtype=np.float64)
    mixture = _mixture_in(means, math.sqrt(ctx.variant.forest_variance), lo, hi)
    trees = _draw_squares(rng, FOREST_SQUARES, mixture, ctx.keep_clear)
    extra = _draw_squares(rng, int(rng.poisson(FOREST_RATE)), _uniform_in((lo, lo, hi, hi)), ctx.keep_clear)
    return np.concatenate([trees, extra], axis=0)


def _moving_wall(rng: np.random.Generator, ctx: _Context) -> FloatArray:
    x = rng.uniform(*MOVING_WALL_X_RANGE)
    y = rng.uniform(*MOVING_WALL_GAP_RANGE)
    x0, x1 = x - MOVING_WALL_WIDTH / 2, x + MOVING_WALL_WIDTH / 2
    g0, g1 = y - MOVING_WALL_GAP / 2, y + MOVING_WALL_GAP / 2
    return _boxes([(x0, 0.0, x1, g0), (x0, g1, x1, 1.0)])


def _baffle(rng: np.random.Generator, ctx: _Context) -> FloatArray:
    cx = rng.uniform(*BAFFLE_X_RANGE)
    cy = rng.uniform(*BAFFLE_Y_RANGE)
    half_pass, half_over = BAFFLE_PASSAGE / 2, BAFFLE_OVERLAP / 2
    left = (cx - half_pass - BAFFLE_WIDTH, 0.0, cx - half_pass, cy + half_over)
    right = (cx + half_pass, cy - half_over, cx + half_pass + BAFFLE_WIDTH, 1.0)
    return _boxes([left, right])


def _maze(rng: np.random.Generator, ctx: _Context) -> FloatArray:
    column = 1.0 / MAZE_COLUMNS
    bottoms = rng.uniform(0.0, 1.0 - MAZE_GAP, size=MAZE_COLUMNS - 1)
    rects: list[Rect] = []
    for i, b in enumerate(bottoms.tolist()):
        x = (i + 1) * column
        x0, x1 = x - MAZE_WALL / 2, x + MAZE_WALL / 2
        rects += [(x0, 0.0, x1, b), (x0, b + MAZE_GAP, x1, 1.0)]
    # tunnel of column j (left wall j - 1, right wall j): from the lowest to the highest gap edge on its
    # sides; the first column starts at the corner y = 0, the last one ends at the corner y = 1
    for j in range(MAZE_COLUMNS):
        sides = [w for w in (j - 1, j) if 0 <= w < bottoms.size]
        floor = 0.0 if j == 0 else min(float(bottoms[w]) for w in sides)
        ceiling = 1.0 if j == MAZE_COLUMNS - 1 else max(float(bottoms[w]) + MAZE_GAP for w in sides)
        xl = 0.0 if j == 0 else j * column + MAZE_WALL / 2
        xr = 1.0 if j == MAZE_COLUMNS - 1 else (j + 1) * column - MAZE_WALL / 2
        if floor > 0.0:
            rects.append((xl, max(0.0, floor - MAZE_WALL), xr, floor))
        if ceiling < 1.0:
            rects.append((xl, ceiling, xr, min(1.0, ceiling + MAZE_WALL)))
    return _boxes(rects)


def _bugtrap(rng: np.random.Generator, ctx: _Context) -> FloatArray:
    orientations = ctx.variant.bugtrap_orientations
    vertical = orientations[int(rng.integers(len(orientations)))] == "vertical"
    cx = rng.uniform(*BUGTRAP_X_RANGE)
    cy = rng.uniform(*BUGTRAP_Y_RANGE)
    t, across, depth = BUGTRAP_WALL, BUGTRAP_ACROSS / 2, BUGTRAP_DEPTH / 2
    if vertical:  # back on the right, arms towards -x
        rects: list[Rect] = [
            (cx + depth - t, cy - across, cx + depth, cy + across),
            (cx - depth, cy + across - t, cx + depth, cy + across),
            (cx - depth, cy - across, cx + depth, cy - across + t),
        ]
    else:  # back on top, arms towards -y
        rects = [
            (cx - across, cy + depth - t, cx + across, cy + depth),
            (cx - across, cy - depth, cx - across + t, cy + depth),
            (cx + across - t, cy - depth, cx + across, cy + depth),
        ]
    side = ctx.variant.bugtrap_square_side
    count = int(rng.poisson(ctx.variant.bugtrap_square_rate))
    squares = _draw_squares(rng, count, _uniform_in(UNIT_BOX), ctx.keep_clear, side=side)
    return np.concatenate([_boxes(rects), squares], axis=0)


_GENERATORS: Mapping[str, Callable[[np.random.Generator, _Context], FloatArray]] = {
    "one_wall": _one_wall,
    "two_wall": _two_wall,
    "forest": _forest,
    "moving_wall": _moving_wall,
    "baffle": _baffle,
    "maze": _maze,
    "bugtrap": _bugtrap,
}


def _keep_clear(points: npt.ArrayLike | None) -> FloatArray:
    """(p, 2) float64 keep-clear points (p = 0 for None)."""
    if points is None:
        return np.zeros((0, 2), dtype=np.float64)
    pts = np.asarray(points, dtype=np.float64)
    if pts.size and (pts.ndim != 2 or pts.shape[1] != 2 or not np.all(np.isfinite(pts))):
        raise ProblemError(f"keep_clear must be finite (p, 2) points, got shape {pts.shape}")
    return pts.reshape(-1, 2)


def world_from_rng(
    model: str,
    rng: np.random.Generator,
    *,
    variant: WorldVariant = PLANAR_VARIANT,
    pattern_seed: int = 0,
    keep_clear: npt.ArrayLike | None = None,
) -> FloatArray:
    """One world of ``model`` drawn from the random stream ``rng`` (advances it).

    Args:
        model: one of :data:`WORLD_MODELS`.
        rng: the world's random stream.
        variant: planar or SE(2) parameters (:data:`PLANAR_VARIANT`, :data:`SE2_VARIANT`).
        pattern_seed: seed of the fixed slot-pattern lists of ``one_wall`` / ``two_wall`` (shared by all
            worlds of a dataset, unlike ``rng``).
        keep_clear: optional (p, 2) points no random square may cover.

    Returns:
        (k, 4) float64 closed boxes (xmin, ymin, xmax, ymax), unit-square units.

    Raises:
        ProblemError: unknown model or malformed ``keep_clear``.
    """
    generator = _GENERATORS.get(model)
    if generator is None:
        raise ProblemError(f"unknown planar world model {model!r}; choose one of {', '.join(WORLD_MODELS)}")
    return generator(rng, _Context(variant, int(pattern_seed), _keep_clear(keep_clear)))


def generate_world(
    model: str,
    *,
    seed: int,
    variant: WorldVariant = PLANAR_VARIANT,
    pattern_seed: int = 0,
    keep_clear: npt.ArrayLike | None = None,
) -> FloatArray:
    """The world of ``model`` drawn with ``numpy.random.default_rng(seed)``: same arguments, same boxes.

    See :func:`world_from_rng` for the arguments and the (k, 4) result.

    Raises:
        ProblemError: unknown model, negative or non-integer seed, malformed ``keep_clear``.
    """
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ProblemError(f"world seed must be a non-negative integer, got {seed!r}")
    return world_from_rng(
        model,
        np.random.default_rng(int(seed)),
        variant=variant,
        pattern_seed=pattern_seed,
        keep_clear=keep_clear,
    )
