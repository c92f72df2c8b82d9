"""The SE(2) domain: a directed Dubins state lattice in the unit square and the box worlds.

Lattice (docs/algorithms.md, "Graphs": the authors' lattice type 2): states (x, y, heading) with x, y on a
grid of ``spacing`` (0.05) over ``bounds`` and 8 headings (multiples of 45 deg). From every state three
motion primitives leave, each the shortest Dubins path (turning radius ``turning_radius`` = 0.99 * 0.1)
to a lattice state:

- axis-aligned heading (0, 90, 180, 270 deg): straight one cell (1, 0), and to (2, +-1) cells while
  turning by +-45 deg;
- diagonal heading (45, 135, 225, 315 deg): straight one diagonal cell (1, 1), and to (1, 2) / (2, 1)
  cells while turning by +45 / -45 deg;

(offsets given for headings 0 and 45 deg, rotated by multiples of 90 deg for the others). The vertices
are the states reachable from the start through primitives whose end lies inside ``bounds``; the edges
are all those primitives. With the defaults this gives V = 3050, E = 7982. The authors' released graph
(``dataset_xyh_*``) has V = 3049, E = 7981: the identical set minus the single state (0.95, 1.0, 135 deg)
and its one incoming arc from (1.0, 0.9, 90 deg). That arc ends exactly on the boundary y = 1, so its
omission is most likely a floating-point bounds test in the authors' code; it is kept here.

Edge lengths are the exact Dubins lengths (the authors store the length of the sampled polyline, e.g.
0.114332 instead of 0.114373 for the turning primitives). Trajectories are sampled at arc-length
spacing at most ``waypoint_spacing`` (0.01), both ends included: 6 / 9 / 13 waypoints for the straight,
diagonal and turning primitives (the authors use 5 / 7 / 11, spacing 0.0114-0.0125). An edge is free iff
every waypoint lies outside every closed box of the world.

Units: the unit square for positions and lengths, radians for headings (counter-clockwise from +x,
in [0, 2 pi)).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.domains.base import LatticeMembers
from drd_planner.domains.dubins import dubins_path
from drd_planner.domains.online import OnlineDefaults
from drd_planner.domains.params import SpecParams
from drd_planner.domains.planar import validate_edge_ids
from drd_planner.domains.planar_worlds import SE2_VARIANT, WORLD_MODELS, as_boxes, generate_world
from drd_planner.exceptions import ProblemError

GridState = tuple[int, int, int]

__all__ = [
    "HEADINGS",
    "Se2Checker",
    "Se2Domain",
    "Se2Lattice",
    "build_lattice",
    "lattice_primitives",
    "points_in_boxes",
]

HEADINGS = 8
HEADING_STEP = 2.0 * math.pi / HEADINGS
_CHUNK_ELEMENTS = 1 << 21  # waypoint x box pairs per vectorised block
_GRID_TOL = 1e-9

# (dx, dy, dheading) in grid cells / heading steps, for heading 0 (even) and heading 1 (odd)
_EVEN_MOTIONS: tuple[GridState, ...] = ((1, 0, 0), (2, 1, 1), (2, -1, -1))
_ODD_MOTIONS: tuple[GridState, ...] = ((1, 1, 0), (1, 2, 1), (2, 1, -1))


@dataclass(frozen=True)
class Primitive:
    """One motion primitive leaving heading ``heading``.

    Attributes:
        heading: start heading index (0..7, multiples of 45 deg).
        offset: (dx, dy) end offset in grid cells.
        end_heading: end heading index.
        length: Dubins length (length unit).
        waypoints: (K, 3) sampled poses (x, y, heading) relative to a start at the origin; the first row
            is (0, 0, heading), the last lies exactly on the lattice point.
    """

    heading: int
    offset: tuple[int, int]
    end_heading: int
    length: float
    waypoints: FloatArray


def _rotate_quarter(dx: int, dy: int, quarters: int) -> tuple[int, int]:
    """(dx, dy) rotated counter-clockwise by ``quarters`` * 90 deg."""
    for _ in range(quarters % 4):
        dx, dy = -dy, dx
    return dx, dy


def lattice_primitives(*, spacing: float, turning_radius: float, waypoint_spacing: float) -> list[Primitive]:
    """The 24 primitives (3 per heading), ordered by heading, then straight / left / right.

    Primitive ``3 * h + j`` leaves heading h; j = 0 straight, 1 turns +45 deg, 2 turns -45 deg.
    """
    out: list[Primitive] = []
    for h in range(HEADINGS):
        motions = _EVEN_MOTIONS if h % 2 == 0 else _ODD_MOTIONS
        for mdx, mdy, mdh in motions:
            dx, dy = _rotate_quarter(mdx, mdy, h // 2)
            h2 = (h + mdh) % HEADINGS
            goal = (dx * spacing, dy * spacing, h2 * HEADING_STEP)
            path = dubins_path((0.0, 0.0, h * HEADING_STEP), goal, radius=turning_radius, headings="unsigned")
            pts = path.sample_evenly(waypoint_spacing)
            pts[0] = (0.0, 0.0, h * HEADING_STEP)
            pts[-1] = goal
            out.append(Primitive(h, (dx, dy), h2, path.length, pts))
    return out


@dataclass(frozen=True)
class Se2Lattice:
    """The explicit lattice graph and the primitive behind every edge.

    Attributes:
        graph: directed graph; ``vertex_states`` (V, 3) are (x, y, heading rad).
        start: start vertex id.
        goal: goal vertex id.
        primitives: the 24 primitives (see :func:`lattice_primitives`).
        edge_primitive: (E,) primitive index of every edge.
        grid_states: (V, 3) int64 (ix, iy, heading index) of every vertex.
    """

    graph: ExplicitGraph
    start: int
    goal: int
    primitives: tuple[Primitive, ...]
    edge_primitive: IntArray
    grid_states: IntArray

    def trajectories(self) -> list[FloatArray]:
        """Per edge a (K_e, 3) array of absolute waypoints (x, y, heading)."""
        states = self.graph.vertex_states
        assert states is not None
        out: list[FloatArray] = []
        for (u, _), p in zip(self.graph.edges.tolist(), self.edge_primitive.tolist(), strict=True):
            wp = self.primitives[p].waypoints.copy()
            wp[:, :2] += states[u, :2]
            out.append(wp)
        return out


def _to_grid(state: Sequence[float], origin: tuple[float, float], spacing: float, what: str) -> GridState:
    """Lattice indices (ix, iy, h) of a state on the lattice, or a ProblemError."""
    x, y, heading = (float(v) for v in state)
    ix, iy = round((x - origin[0]) / spacing), round((y - origin[1]) / spacing)
    h = round(heading / HEADING_STEP)
    exact = (origin[0] + ix * spacing, origin[1] + iy * spacing, h * HEADING_STEP)
    if max(abs(exact[0] - x), abs(exact[1] - y), abs(exact[2] - heading)) > _GRID_TOL:
        raise ProblemError(
            f"SE(2) {what} {tuple(state)} is not a lattice state (x, y multiples of {spacing} from "
            f"{origin}, heading a multiple of 45 deg in radians)"
        )
    return int(ix), int(iy), int(h) % HEADINGS


def build_lattice(
    *,
    spacing: float = 0.05,
    turning_radius: float = 0.099,
    waypoint_spacing: float = 0.01,
    bounds: tuple[float, float, float, float] = (0.0, 0.0, 1.0, 1.0),
    start: tuple[float, float, float] = (0.05, 0.5, 0.0),
    goal: tuple[float, float, float] = (0.95, 0.5, 0.0),
) -> Se2Lattice:
    """Build the lattice by breadth-first expansion from ``start`` (vertex 0).

    Vertices are numbered in the order they are reached (primitives tried straight, left, right); edges
    in the order they are generated. Headings of the vertex states are in [0, 2 pi).

    Raises:
        ProblemError: bad parameters, bounds not a whole number of cells, start/goal off the lattice or
            outside the bounds, or a goal unreachable from the start.
    """
    for name, value in (
        ("spacing", spacing),
        ("turning_radius", turning_radius),
        ("waypoint_spacing", waypoint_spacing),
    ):
        if not (math.isfinite(value) and value > 0):
            raise ProblemError(f"SE(2) lattice {name} must be positive and finite, got {value}")
    xmin, ymin, xmax, ymax = (float(b) for b in bounds)
    cells = ((xmax - xmin) / spacing, (ymax - ymin) / spacing)
    if min(cells) < 1 or any(abs(c - round(c)) > 1e-6 for c in cells):
        raise ProblemError(f"SE(2) bounds {bounds} must span a positive whole number of {spacing} cells")
    nx, ny = round(cells[0]), round(cells[1])
    origin = (xmin, ymin)
    s0 = _to_grid(start, origin, spacing, "start")
    g0 = _to_grid(goal, origin, spacing, "goal")
    for what, s in (("start", s0), ("goal", g0)):
        if not (0 <= s[0] <= nx and 0 <= s[1] <= ny):
            raise ProblemError(f"SE(2) {what} lies outside the bounds {bounds}")
    prims = lattice_primitives(spacing=spacing, turning_radius=turning_radius, waypoint_spacing=waypoint_spacing)
    index: dict[GridState, int] = {s0: 0}
    order: list[GridState] = [s0]
    edges: list[tuple[int, int, int]] = []
    queue: deque[GridState] = deque([s0])
    while queue:
        u = queue.popleft()
        for j in range(3):
            p = prims[3 * u[2] + j]
            v = (u[0] + p.offset[0], u[1] + p.offset[1], p.end_heading)
            if not (0 <= v[0] <= nx and 0 <= v[1] <= ny):
                continue
            if v not in index:
                index[v] = len(order)
                order.append(v)
                queue.append(v)
            edges.append((index[u], index[v], 3 * u[2] + j))
    if g0 not in index:
        raise ProblemError(f"SE(2) goal {goal} is not reachable from the start {start} on the lattice")
    grid = np.array(order, dtype=np.int64)
    states = np.stack(
        [xmin + grid[:, 0] * spacing, ymin + grid[:, 1] * spacing, grid[:, 2] * HEADING_STEP], axis=1
    ).astype(np.float64)
    e = np.array(edges, dtype=np.int64)
    lengths = np.array([prims[p].length for p in e[:, 2].tolist()], dtype=np.float64)
    graph = ExplicitGraph(e[:, :2], lengths, len(order), directed=True, vertex_states=states)
    return Se2Lattice(graph, 0, index[g0], tuple(prims), np.asarray(e[:, 2], dtype=np.int64), grid)


# --------------------------------------------------------------------------------------------------
# Checking


def points_in_boxes(points: npt.ArrayLike, boxes: npt.ArrayLike) -> BoolArray:
    """Whether each point lies in some closed axis-aligned box (boundary counts as inside).

    Args:
        points: (P, 2) x, y.
        boxes: (k, 4) boxes (xmin, ymin, xmax, ymax).

    Returns:
        (P,) bool, True where the point is inside (or on) at least one box. Works in blocks of at most
        about two million point x box pairs.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    bx = as_boxes(boxes)
    inside = np.zeros(pts.shape[0], dtype=bool)
    if bx.shape[0] == 0 or pts.shape[0] == 0:
        return inside
    rows = max(1, _CHUNK_ELEMENTS // bx.shape[0])
    for lo in range(0, pts.shape[0], rows):
        x = pts[lo : lo + rows, 0, None]
        y = pts[lo : lo + rows, 1, None]
        hit = (x >= bx[:, 0]) & (x <= bx[:, 2]) & (y >= bx[:, 1]) & (y <= bx[:, 3])
        inside[lo : lo + rows] = hit.any(axis=1)
    return inside


class Se2Checker:
    """Edge checker of one box world: an edge is free iff none of its waypoints is in a box."""

    def __init__(self, lattice: Se2Lattice, boxes: npt.ArrayLike) -> None:
        """Check the edges of ``lattice`` against (k, 4) closed boxes."""
        states = lattice.graph.vertex_states
        assert states is not None
        self._origins = states[lattice.graph.edges[:, 0], :2]
        self._primitive = lattice.edge_primitive
        self._offsets = [p.waypoints[:, :2] for p in lattice.primitives]
        self._boxes = as_boxes(boxes)
        self._num_edges = lattice.graph.num_edges

    @property
    def boxes(self) -> FloatArray:
        """(k, 4) boxes of the world."""
        return self._boxes

    def check(self, edge: int) -> bool:
        """True when edge ``edge`` is collision-free."""
        return bool(self.check_many(np.array([edge]))[0])

    def check_many(self, edges: npt.ArrayLike) -> BoolArray:
        """(K,) bool, True where each of the (K,) edge ids is collision-free (all waypoints outside)."""
        ids = validate_edge_ids(edges, self._num_edges)
        free = np.ones(ids.size, dtype=bool)
        if self._boxes.shape[0] == 0 or ids.size == 0:
            return free
        prim = self._primitive[ids]
        for p in np.unique(prim).tolist():
            where = np.flatnonzero(prim == p)
            offsets = self._offsets[p]
            pts = self._origins[ids[where]][:, None, :] + offsets[None, :, :]
            hit = points_in_boxes(pts.reshape(-1, 2), self._boxes).reshape(where.size, offsets.shape[0])
            free[where] = ~hit.any(axis=1)
        return free


# --------------------------------------------------------------------------------------------------
# Domain


def _state_field(name: str, value: object) -> tuple[float, float, float]:
    """A finite (x, y, heading) triple, or a ProblemError naming the field."""
    try:
        triple = tuple(float(v) for v in value)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise ProblemError(f"SE(2) domain: {name} must be [x, y, heading], got {value!r}") from None
    if len(triple) != 3 or not all(math.isfinite(v) for v in triple):
        raise ProblemError(f"SE(2) domain: {name} must be three finite numbers, got {value!r}")
    return triple[0], triple[1], triple[2]


def _number_field(name: str, value: object) -> float:
    """``value`` as a float, or a ProblemError naming the field."""
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise ProblemError(f"SE(2) domain: {name} must be a number, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class Se2Domain(SpecParams, LatticeMembers[Se2Lattice], OnlineDefaults):
    """The SE(2) domain: the Dubins state lattice and the box worlds with SE(2) parameters.

    The graph is the directed lattice (:attr:`lattice`, its primitives and the primitive of every edge),
    ``vertex_states`` (V, 3) = (x, y, heading rad); the start vertex (0) is the vertex of ``start_state``,
    the goal vertex the vertex of ``goal_state``.

    Attributes:
        spacing: xy lattice spacing (unit square).
        turning_radius: Dubins turning radius (unit square).
        waypoint_spacing: largest arc-length gap between checked waypoints (unit square).
        bounds: (xmin, ymin, xmax, ymax) of the lattice (unit square).
        start_state: start state (x, y, heading) on the lattice (unit square), the heading in radians.
        goal_state: goal state (x, y, heading) on the lattice (unit square), the heading in radians.
        pattern_seed: seed of the fixed slot-pattern lists of ``one_wall`` / ``two_wall`` (seed).
        keep_clear: keep random squares off the start and goal positions (flag); the authors did not.
    """

    SPEC_LABEL: ClassVar[str] = "se2"

    spacing: float = 0.05
    turning_radius: float = 0.099
    waypoint_spacing: float = 0.01
    bounds: tuple[float, float, float, float] = (0.0, 0.0, 1.0, 1.0)
    start_state: tuple[float, float, float] = (0.05, 0.5, 0.0)
    goal_state: tuple[float, float, float] = (0.95, 0.5, 0.0)
    pattern_seed: int = 0
    keep_clear: bool = False
    _lattice: Se2Lattice = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        for name in ("spacing", "turning_radius", "waypoint_spacing"):
            object.__setattr__(self, name, _number_field(name, getattr(self, name)))
        try:
            bounds = tuple(_number_field("bounds", b) for b in self.bounds)
        except TypeError:
            raise ProblemError(f"SE(2) domain: bounds must be [xmin, ymin, xmax, ymax], got {self.bounds!r}") from None
        if len(bounds) != 4:
            raise ProblemError(f"SE(2) domain: bounds must have 4 numbers, got {self.bounds!r}")
        object.__setattr__(self, "bounds", bounds)
        object.__setattr__(self, "start_state", _state_field("start_state", self.start_state))
        object.__setattr__(self, "goal_state", _state_field("goal_state", self.goal_state))
        ps = self.pattern_seed
        if isinstance(ps, bool) or not isinstance(ps, int | np.integer) or ps < 0:
            raise ProblemError(f"SE(2) domain: pattern_seed must be a non-negative integer, got {ps!r}")
        object.__setattr__(self, "pattern_seed", int(ps))
        if not isinstance(self.keep_clear, bool):
            raise ProblemError(f"SE(2) domain: keep_clear must be true or false, got {self.keep_clear!r}")
        lattice = build_lattice(
            spacing=self.spacing,
            turning_radius=self.turning_radius,
            waypoint_spacing=self.waypoint_spacing,
            bounds=self.bounds,
            start=self.start_state,
            goal=self.goal_state,
        )
        object.__setattr__(self, "_lattice", lattice)

    def spec(self) -> dict[str, Any]:
        """JSON-able parameters (tuples as lists); ``Se2Domain.from_spec(d.spec()) == d``."""
        return self.to_spec()

    @property
    def name(self) -> str:
        """``"se2"``."""
        return "se2"

    @property
    def state_columns(self) -> str:
        """A point of the unit square and a heading."""
        return "x, y (unit square); heading rad"

    @property
    def world_models(self) -> tuple[str, ...]:
        """All seven world models, with their SE(2) parameters."""
        return WORLD_MODELS

    def make_world(self, model: str, seed: int) -> FloatArray:
        """The (k, 4) boxes of ``model`` drawn with ``seed`` (SE(2) variant of the models)."""
        clear = np.array([self.start_state[:2], self.goal_state[:2]]) if self.keep_clear else None
        return generate_world(model, seed=seed, variant=SE2_VARIANT, pattern_seed=self.pattern_seed, keep_clear=clear)

    def checker(self, world: npt.ArrayLike) -> Se2Checker:
        """A waypoint checker of the lattice edges against the (k, 4) boxes ``world``."""
        return Se2Checker(self._lattice, world)

    def edge_trajectories(self) -> list[FloatArray]:
        """Per edge (graph order) a (K_e, 3) array of waypoints (x, y, heading rad)."""
        return self._lattice.trajectories()

    def check_metadata(self) -> dict[str, Any]:
        """How edges are checked (waypoints in closed boxes, point robot, no margin)."""
        return {
            "method": "every Dubins waypoint outside every closed axis-aligned box",
            "waypoint_spacing": self.waypoint_spacing,
            "turning_radius": self.turning_radius,
            "vehicle": "point",
            "margin": 0.0,
            "length_unit": "unit square (dimensionless)",
            "heading_unit": "rad",
            "world_variant": SE2_VARIANT.name,
            "pattern_seed": self.pattern_seed,
            "keep_clear": self.keep_clear,
        }
