"""The helicopter's state lattice in (x, y, z, heading) with Dubins motion primitives.

Like the authors' XYHZ lattice (ALGORITHMS.md section 6.1, ``XYHZAnalyticLattice.m``; their
``dataset_heli_canyon_1`` uses a 50 m grid, 8 headings and Dubins primitives of turning radius
100 m over x in [0, 700] m, y in [-250, 250] m, one altitude), vertices are states on a regular grid:

- positions (x, y) at the multiples of ``xy_spacing`` inside ``x_range`` x ``y_range``;
- headings at multiples of 45 degrees with ``|heading| <= max_heading_deg`` (default: forward-going,
  -90..90 degrees, like the authors' canyon graph);
- altitudes at the ``z_levels`` (metres above the world datum z = 0).

Edges are motion primitives: for heading 0 (and rotated by multiples of 90 degrees) the
``axis_primitives``, for heading 45 degrees the ``diagonal_primitives``, each an offset in grid cells and
a heading change in 45-degree steps, flown as the shortest Dubins path of the turning radius. The
defaults are the authors' primitives: from heading 0 a 50 m straight, lane changes to (150, +-50),
45-degree turns to (100, +-50), 90-degree turns to (100, +-100) (exact quarter circles of the 100 m
radius) and to (150, +-100); from heading 45 degrees a diagonal straight and 45-degree turns to (50, 100)
and (100, 50). Primitives whose horizontal length is at least ``level_spacing / max_climb_gradient``
also come in climb and descend variants that change altitude by one level at a constant gradient (a
helix on arcs); which primitives may climb is ``climb`` ("none", "straight" or "all"). With the defaults
(3 levels 25 m apart, gradient 0.5, straights only) the pruned graph has 731 vertices and 3012 edges.

Only vertices and edges that lie on some start-goal path remain (forward reachability from the start
intersected with backward reachability from the goal). Vertex ids and edge order are deterministic.

Units: metres, radians. Edge lengths are 3D arc lengths in metres.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from scipy.sparse import csr_array
from scipy.sparse.csgraph import breadth_first_order

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.domains.helicopter_dubins import DubinsPath, dubins_path, wrap_angle
from drd_planner.domains.helicopter_params import params_from_dict, params_to_dict
from drd_planner.exceptions import ProblemError

__all__ = ["HelicopterLattice", "LatticeParams", "build_lattice"]

NUM_HEADINGS = 8
HEADING_STEP = 2.0 * math.pi / NUM_HEADINGS
CLIMB_MODES: tuple[str, ...] = ("none", "straight", "all")

Primitive = tuple[int, int, int]


def _positive_number(value: Any, what: str) -> float:
    """``value`` as a finite float > 0, else ProblemError."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ProblemError(f"lattice {what} must be a number, got {value!r}") from None
    if not (math.isfinite(number) and number > 0.0):
        raise ProblemError(f"lattice {what} must be positive and finite, got {value!r}")
    return number


def _as_primitives(value: Any, what: str) -> tuple[Primitive, ...]:
    """Validated primitive tuples (dx cells, dy cells, heading steps of 45 degrees)."""
    try:
        prims = tuple((int(p[0]), int(p[1]), int(p[2])) for p in value)
        ok = all(len(p) == 3 for p in value)
    except (TypeError, ValueError, IndexError) as exc:
        raise ProblemError(f"{what} must be a list of [dx, dy, dheading] integer triples: {exc}") from None
    if not ok or not prims:
        raise ProblemError(f"{what} must be a non-empty list of [dx, dy, dheading] integer triples")
    if any(p[0] == 0 and p[1] == 0 for p in prims):
        raise ProblemError(f"{what}: a primitive must move ({prims})")
    if len(set(prims)) != len(prims):
        raise ProblemError(f"{what}: duplicate primitives ({prims})")
    return prims


@dataclass(frozen=True)
class LatticeParams:
    """Parameters of the helicopter lattice (all JSON-able; see the module docstring).

    Attributes:
        x_range: (min, max) x of the grid, metres.
        y_range: (min, max) y of the grid, metres.
        xy_spacing: grid spacing in x and y, metres.
        z_levels: increasing altitudes of the levels, metres.
        turning_radius: Dubins turning radius, metres.
        max_heading_deg: largest |heading| kept, degrees (180 keeps all 8 headings).
        sample_spacing: largest arc-length step between trajectory samples, metres.
        climb: which primitives get climb/descend variants: "none", "straight" or "all".
        max_climb_gradient: largest |dz| / horizontal length of a climbing primitive.
        start: (x, y) metres of the start; heading 0, altitude level ``start_level``.
        goal: (x, y) metres of the goal; heading 0, altitude level ``goal_level``.
        start_level: index into ``z_levels`` of the start (-1: the middle level).
        goal_level: index into ``z_levels`` of the goal (-1: the middle level).
        axis_primitives: (dx cells, dy cells, heading steps) for heading 0.
        diagonal_primitives: (dx cells, dy cells, heading steps) for heading 45 degrees.
    """

    x_range: tuple[float, float] = (0.0, 700.0)
    y_range: tuple[float, float] = (-250.0, 250.0)
    xy_spacing: float = 50.0
    z_levels: tuple[float, ...] = (40.0, 65.0, 90.0)
    turning_radius: float = 100.0
    max_heading_deg: float = 90.0
    sample_spacing: float = 5.0
    climb: str = "straight"
    max_climb_gradient: float = 0.5
    start: tuple[float, float] = (0.0, 0.0)
    goal: tuple[float, float] = (700.0, 0.0)
    start_level: int = -1
    goal_level: int = -1
    axis_primitives: tuple[Primitive, ...] = (
        (1, 0, 0),
        (3, 1, 0),
        (3, -1, 0),
        (2, 1, 1),
        (2, -1, -1),
        (2, 2, 2),
        (2, -2, -2),
        (3, 2, 2),
        (3, -2, -2),
    )
    diagonal_primitives: tuple[Primitive, ...] = ((1, 1, 0), (1, 2, 1), (2, 1, -1))

    def __post_init__(self) -> None:
        def pair(name: str) -> tuple[float, float]:
            v = getattr(self, name)
            try:
                a, b = (float(t) for t in v)
            except (TypeError, ValueError):
                raise ProblemError(f"lattice {name} must be a pair of numbers, got {v!r}") from None
            if not (math.isfinite(a) and math.isfinite(b)):
                raise ProblemError(f"lattice {name} must be finite, got {v!r}")
            return a, b

        for name in ("x_range", "y_range", "start", "goal"):
            object.__setattr__(self, name, pair(name))
        for name in ("x_range", "y_range"):
            lo, hi = getattr(self, name)
            if not lo < hi:
                raise ProblemError(f"lattice {name} must have min < max, got {(lo, hi)}")
        for name in (
            "xy_spacing",
            "turning_radius",
            "sample_spacing",
            "max_climb_gradient",
            "max_heading_deg",
        ):
            object.__setattr__(self, name, _positive_number(getattr(self, name), name))
        try:
            levels = tuple(float(z) for z in self.z_levels)
        except (TypeError, ValueError):
            raise ProblemError(f"lattice z_levels must be a list of numbers, got {self.z_levels!r}") from None
        if not levels or not all(math.isfinite(z) for z in levels) or any(np.diff(levels) <= 0):
            raise ProblemError(f"lattice z_levels must be finite and strictly increasing, got {levels}")
        if len(levels) > 2 and np.ptp(np.diff(levels)) > 1e-6:
            raise ProblemError(f"lattice z_levels must be equally spaced, got {levels}")
        object.__setattr__(self, "z_levels", levels)
        if self.climb not in CLIMB_MODES:
            raise ProblemError(f"lattice climb must be one of {CLIMB_MODES}, got {self.climb!r}")
        for name in ("start_level", "goal_level"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not -1 <= v < len(levels):
                raise ProblemError(f"lattice {name} must be -1 (middle) or in [0, {len(levels)}), got {v}")
            object.__setattr__(self, name, int(v))
        object.__setattr__(self, "axis_primitives", _as_primitives(self.axis_primitives, "axis_primitives"))
        object.__setattr__(
            self, "diagonal_primitives", _as_primitives(self.diagonal_primitives, "diagonal_primitives")
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict (lists for tuples) that :meth:`from_dict` turns back into equal parameters."""
        return params_to_dict(self)

    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> LatticeParams:
        """Parameters from a (partial) dict; missing keys take the defaults, unknown keys raise ProblemError."""
        return params_from_dict(cls, values, what="lattice")

    def level_index(self, which: int) -> int:
        """The level index of ``start_level``/``goal_level`` value ``which`` (-1 = middle level)."""
        return len(self.z_levels) // 2 if which < 0 else which


@dataclass(frozen=True)
class HelicopterLattice:
    """A built lattice: graph, start/goal, and the sampled trajectory of every edge.

    Attributes:
        params: the parameters it was built from.
        graph: directed graph; ``vertex_states`` (V, 4) = x m, y m, z m, heading rad in [-pi, pi).
        start: start vertex id.
        goal: goal vertex id.
        points: (P, 4) trajectory samples of all edges (x, y, z m, heading rad), edge after edge.
        offsets: (E + 1,) edge e owns ``points[offsets[e]:offsets[e + 1]]`` (first = its source state,
            last = its target state).
        primitive: (E,) index of each edge's primitive in ``primitive_names``.
        climb: (E,) altitude change in levels (-1, 0, +1).
        primitive_names: names like "axis(1,1,2)" / "diagonal(1,1,0)".
        primitive_paths: the Dubins path of each primitive, from the origin with heading 0 or 45 degrees.
    """

    params: LatticeParams
    graph: ExplicitGraph
    start: int
    goal: int
    points: FloatArray
    offsets: IntArray
    primitive: IntArray
    climb: IntArray
    primitive_names: tuple[str, ...]
    primitive_paths: tuple[DubinsPath, ...]

    def trajectory(self, edge: int) -> FloatArray:
        """(K_e, 4) samples of one edge: x, y, z (m), heading (rad)."""
        if not 0 <= edge < self.graph.num_edges:
            raise ProblemError(f"edge id {edge} out of range [0, {self.graph.num_edges})")
        return self.points[self.offsets[edge] : self.offsets[edge + 1]]

    def trajectories(self) -> list[FloatArray]:
        """Every edge's (K_e, 4) samples in graph order (views into :attr:`points`)."""
        bounds = self.offsets.tolist()
        return [self.points[a:b] for a, b in itertools.pairwise(bounds)]

    @property
    def edge_of_point(self) -> IntArray:
        """(P,) edge id of every trajectory sample."""
        return np.repeat(np.arange(self.graph.num_edges, dtype=np.int64), np.diff(self.offsets))


class _Group(NamedTuple):
    """Edges of one (heading, primitive, climb) combination before pruning."""

    src: IntArray
    dst: IntArray
    proto: int
    climb: int
    quarter: int


def _grid_values(lo: float, hi: float, spacing: float) -> FloatArray:
    """Multiples of ``spacing`` in [lo, hi] (1e-9 tolerance)."""
    first = math.ceil(lo / spacing - 1e-9)
    last = math.floor(hi / spacing + 1e-9)
    if last < first:
        raise ProblemError(f"no grid point of spacing {spacing} m in [{lo}, {hi}]")
    return np.arange(first, last + 1, dtype=np.float64) * spacing


def _grid_index(values: FloatArray, v: float, what: str) -> int:
    """Index of the grid value equal to ``v``."""
    i = int(np.argmin(np.abs(values - v)))
    if abs(values[i] - v) > 1e-6:
        raise ProblemError(f"{what} {v} m is not on the lattice grid {values.tolist()}")
    return i


def _rotate_cells(dx: int, dy: int, quarter_turns: int) -> tuple[int, int]:
    """Rotate an integer offset by ``quarter_turns`` x 90 degrees counter-clockwise."""
    for _ in range(quarter_turns % 4):
        dx, dy = -dy, dx
    return dx, dy


def _template(path: DubinsPath, dz: float, spacing: float) -> tuple[FloatArray, float]:
    """Samples (n, 4) of a primitive from the origin (z from 0 to dz) and its 3D length in metres."""
    horizontal = path.length
    length = math.hypot(horizontal, dz)
    n = max(2, math.ceil(length / spacing - 1e-9) + 1)
    s = np.linspace(0.0, horizontal, n)
    pose = path.sample(s)
    out = np.empty((n, 4), dtype=np.float64)
    out[:, 0:2] = pose[:, 0:2]
    out[:, 2] = dz * s / horizontal
    out[:, 3] = pose[:, 2]
    return out, length


def build_lattice(params: LatticeParams | None = None) -> HelicopterLattice:
    """Build the pruned lattice graph and all edge trajectories (vectorised over the grid).

    Raises:
        ProblemError: inconsistent parameters (start/goal off the grid, a primitive that needs a loop
            because the turning radius is too large for the spacing), or a goal unreachable from the start.
    """
    p = params or LatticeParams()
    xs = _grid_values(*p.x_range, p.xy_spacing)
    ys = _grid_values(*p.y_range, p.xy_spacing)
    zs = np.asarray(p.z_levels, dtype=np.float64)
    nx, ny, nz = xs.size, ys.size, zs.size
    headings = wrap_angle(np.arange(NUM_HEADINGS) * HEADING_STEP)
    allowed = np.abs(headings) <= math.radians(p.max_heading_deg) + 1e-9
    level_gap = float(np.min(np.diff(zs))) if nz > 1 else math.inf

    # Primitive prototypes: Dubins paths from the origin at heading 0 (axis) or 45 degrees (diagonal).
    protos: list[tuple[int, Primitive, DubinsPath]] = []
    names: list[str] = []
    for cls, prims in ((0, p.axis_primitives), (1, p.diagonal_primitives)):
        for prim in prims:
            h0 = cls * HEADING_STEP
            end = (prim[0] * p.xy_spacing, prim[1] * p.xy_spacing, h0 + prim[2] * HEADING_STEP)
            path = dubins_path((0.0, 0.0, h0), end, radius=p.turning_radius)
            if path.turning > abs(prim[2]) * HEADING_STEP + math.pi / 2 + 1e-9:
                raise ProblemError(
                    f"primitive {prim} ({'diagonal' if cls else 'axis'}) needs a loop ({path.word}, "
                    f"{math.degrees(path.turning):.0f} deg of turning) with turning radius {p.turning_radius} m "
                    f"at spacing {p.xy_spacing} m; drop it or change the spacing/radius"
                )
            protos.append((cls, prim, path))
            names.append(f"{'diagonal' if cls else 'axis'}({prim[0]},{prim[1]},{prim[2]})")

    ix, iy, iz = (a.ravel() for a in np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij"))

    def state_id(i: IntArray, j: IntArray, k: IntArray | int, lvl: IntArray) -> IntArray:
        return np.asarray(((i * ny + j) * NUM_HEADINGS + k) * nz + lvl, dtype=np.int64)

    groups: list[_Group] = []
    for k in np.flatnonzero(allowed).tolist():
        cls, quarter = k % 2, k // 2
        for proto_id, (pcls, prim, path) in enumerate(protos):
            if pcls != cls:
                continue
            k2 = (k + prim[2]) % NUM_HEADINGS
            if not allowed[k2]:
                continue
            dx, dy = _rotate_cells(prim[0], prim[1], quarter)
            climbs = [0]
            may_climb = p.climb == "all" or (p.climb == "straight" and path.turning < 1e-9)
            if may_climb and path.length * p.max_climb_gradient >= level_gap - 1e-9:
                climbs = [0, 1, -1]
            for dl in climbs:
                tx, ty, tz = ix + dx, iy + dy, iz + dl
                ok = (tx >= 0) & (tx < nx) & (ty >= 0) & (ty < ny) & (tz >= 0) & (tz < nz)
                if not ok.any():
                    continue
                src = state_id(ix[ok], iy[ok], k, iz[ok])
                dst = state_id(tx[ok], ty[ok], k2, tz[ok])
                groups.append(_Group(src, dst, proto_id, dl, quarter))
    if not groups:
        raise ProblemError("the lattice has no edges; check the ranges, spacing and primitives")

    num_states = nx * ny * NUM_HEADINGS * nz
    src_all = np.concatenate([g.src for g in groups])
    dst_all = np.concatenate([g.dst for g in groups])
    start_state = int(
        state_id(
            np.array([_grid_index(xs, p.start[0], "start x")]),
            np.array([_grid_index(ys, p.start[1], "start y")]),
            0,
            np.array([p.level_index(p.start_level)]),
        )[0]
    )
    goal_state = int(
        state_id(
            np.array([_grid_index(xs, p.goal[0], "goal x")]),
            np.array([_grid_index(ys, p.goal[1], "goal y")]),
            0,
            np.array([p.level_index(p.goal_level)]),
        )[0]
    )
    if start_state == goal_state:
        raise ProblemError("lattice start and goal are the same state")
    adjacency = csr_array(
        (np.ones(src_all.size), (src_all, dst_all)), shape=(num_states, num_states), dtype=np.float64
    )
    forward = np.zeros(num_states, dtype=bool)
    forward[breadth_first_order(adjacency, start_state, directed=True, return_predecessors=False)] = True
    backward = np.zeros(num_states, dtype=bool)
    backward[
        breadth_first_order(adjacency.T.tocsr(), goal_state, directed=True, return_predecessors=False)
    ] = True
    keep_state = forward & backward
    if not keep_state[goal_state]:
        raise ProblemError(
            "the lattice goal is not reachable from the start; widen the ranges or add primitives"
        )
    new_id = np.full(num_states, -1, dtype=np.int64)
    kept_states = np.flatnonzero(keep_state)
    new_id[kept_states] = np.arange(kept_states.size)

    # Vertex states (x, y, z, heading) of the kept states.
    k_level = kept_states % nz
    rest = kept_states // nz
    k_head = rest % NUM_HEADINGS
    rest //= NUM_HEADINGS
    states = np.stack([xs[rest // ny], ys[rest % ny], zs[k_level], headings[k_head]], axis=1)

    # Edges of each group that survive, with their templates.
    edge_src: list[IntArray] = []
    edge_dst: list[IntArray] = []
    edge_group: list[IntArray] = []
    edge_member: list[IntArray] = []
    for gi, g in enumerate(groups):
        ok = keep_state[g.src] & keep_state[g.dst]
        edge_src.append(new_id[g.src[ok]])
        edge_dst.append(new_id[g.dst[ok]])
        edge_group.append(np.full(int(ok.sum()), gi, dtype=np.int64))
        edge_member.append(np.flatnonzero(ok))
    u = np.concatenate(edge_src)
    v = np.concatenate(edge_dst)
    grp = np.concatenate(edge_group)
    member = np.concatenate(edge_member)
    order = np.lexsort((v, u))
    u, v, grp, member = u[order], v[order], grp[order], member[order]
    num_edges = u.size

    templates: list[tuple[FloatArray, float]] = []
    for g in groups:
        path = protos[g.proto][2]
        tpl, length = _template(path, g.climb * level_gap if g.climb else 0.0, p.sample_spacing)
        c, s = math.cos(g.quarter * math.pi / 2), math.sin(g.quarter * math.pi / 2)
        rotated = tpl.copy()
        rotated[:, 0] = c * tpl[:, 0] - s * tpl[:, 1]
        rotated[:, 1] = s * tpl[:, 0] + c * tpl[:, 1]
        rotated[:, 3] = wrap_angle(tpl[:, 3] + g.quarter * math.pi / 2)
        templates.append((rotated, length))

    counts = np.array([templates[g][0].shape[0] for g in grp.tolist()], dtype=np.int64)
    offsets = np.zeros(num_edges + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    points = np.empty((int(offsets[-1]), 4), dtype=np.float64)
    lengths = np.empty(num_edges, dtype=np.float64)
    proto_of_edge = np.empty(num_edges, dtype=np.int64)
    climb_of_edge = np.empty(num_edges, dtype=np.int64)
    for gi, (tpl, length) in enumerate(templates):
        sel = np.flatnonzero(grp == gi)
        if sel.size == 0:
            continue
        base = states[u[sel]]
        idx = offsets[sel][:, None] + np.arange(tpl.shape[0])[None, :]
        block = np.broadcast_to(tpl, (sel.size, *tpl.shape)).copy()
        block[:, :, 0:3] += base[:, None, 0:3]
        points[idx.ravel()] = block.reshape(-1, 4)
        lengths[sel] = length
        proto_of_edge[sel] = groups[gi].proto
        climb_of_edge[sel] = groups[gi].climb
    # Snap the end samples to the exact lattice states (removes rounding of the Dubins sampling).
    points[offsets[:-1]] = states[u]
    points[offsets[1:] - 1] = states[v]

    graph = ExplicitGraph(
        edges=np.stack([u, v], axis=1),
        lengths=lengths,
        num_vertices=int(kept_states.size),
        directed=True,
        vertex_states=states,
    )
    return HelicopterLattice(
        params=p,
        graph=graph,
        start=int(new_id[start_state]),
        goal=int(new_id[goal_state]),
        points=points,
        offsets=offsets,
        primitive=proto_of_edge,
        climb=climb_of_edge,
        primitive_names=tuple(names),
        primitive_paths=tuple(path for _c, _p, path in protos),
    )
