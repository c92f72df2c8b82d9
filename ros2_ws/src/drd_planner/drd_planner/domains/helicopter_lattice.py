"""The helicopter's state lattice in (x, y, z, heading) with Dubins motion primitives.

Like the authors' XYHZ lattice (docs/algorithms.md, "Graphs"; ``XYHZAnalyticLattice.m``; their
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
from typing import NamedTuple

import numpy as np
from scipy.sparse import csr_array
from scipy.sparse.csgraph import breadth_first_order

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.graph import ExplicitGraph
from drd_planner.domains.dubins import DubinsPath, dubins_path, wrap_angle
from drd_planner.domains.helicopter_lattice_params import LatticeParams, Primitive
from drd_planner.exceptions import ProblemError

__all__ = ["HelicopterLattice", "LatticeParams", "build_lattice"]

NUM_HEADINGS = 8
HEADING_STEP = 2.0 * math.pi / NUM_HEADINGS


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


class _Prototype(NamedTuple):
    """A primitive from the origin at heading 0 (class 0, axis) or 45 degrees (class 1, diagonal)."""

    cls: int
    prim: Primitive
    path: DubinsPath

    @property
    def name(self) -> str:
        """E.g. "axis(1,1,2)" / "diagonal(1,1,0)"."""
        return f"{'diagonal' if self.cls else 'axis'}({self.prim[0]},{self.prim[1]},{self.prim[2]})"


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


class _StateGrid:
    """The full (unpruned) state grid: positions x, y, 8 headings and the altitude levels.

    State ids are ``((ix * ny + iy) * NUM_HEADINGS + k) * nz + level``.
    """

    def __init__(self, p: LatticeParams) -> None:
        self.xs = _grid_values(*p.x_range, p.xy_spacing)
        self.ys = _grid_values(*p.y_range, p.xy_spacing)
        self.zs = np.asarray(p.z_levels, dtype=np.float64)
        self.nx, self.ny, self.nz = self.xs.size, self.ys.size, self.zs.size
        self.headings = wrap_angle(np.arange(NUM_HEADINGS) * HEADING_STEP)
        self.allowed = np.abs(self.headings) <= math.radians(p.max_heading_deg) + 1e-9
        self.level_gap = float(np.min(np.diff(self.zs))) if self.nz > 1 else math.inf
        # (ix, iy, iz) of every (position, level), ix slowest
        self.cells = tuple(
            a.ravel() for a in np.meshgrid(np.arange(self.nx), np.arange(self.ny), np.arange(self.nz), indexing="ij")
        )

    @property
    def num_states(self) -> int:
        """Number of states of the full grid."""
        return self.nx * self.ny * NUM_HEADINGS * self.nz

    def state_id(self, i: IntArray, j: IntArray, k: IntArray | int, lvl: IntArray) -> IntArray:
        """Ids of the states at grid indices (i, j), heading index k and level ``lvl``."""
        return np.asarray(((i * self.ny + j) * NUM_HEADINGS + k) * self.nz + lvl, dtype=np.int64)

    def endpoint(self, xy: tuple[float, float], level: int, what: str) -> int:
        """The id of the heading-0 state at position ``xy`` (metres, on the grid) and level index ``level``."""
        return int(
            self.state_id(
                np.array([_grid_index(self.xs, xy[0], f"{what} x")]),
                np.array([_grid_index(self.ys, xy[1], f"{what} y")]),
                0,
                np.array([level]),
            )[0]
        )

    def states(self, ids: IntArray) -> FloatArray:
        """(n, 4) x, y, z (m), heading (rad) of states ``ids`` (n,)."""
        k_level = ids % self.nz
        rest = ids // self.nz
        k_head = rest % NUM_HEADINGS
        rest //= NUM_HEADINGS
        return np.stack(
            [self.xs[rest // self.ny], self.ys[rest % self.ny], self.zs[k_level], self.headings[k_head]],
            axis=1,
        )


def _prototypes(p: LatticeParams) -> list[_Prototype]:
    """The Dubins path of every primitive from the origin; ProblemError for one that needs a loop."""
    protos: list[_Prototype] = []
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
            protos.append(_Prototype(cls, prim, path))
    return protos


def _climbs(p: LatticeParams, path: DubinsPath, level_gap: float) -> list[int]:
    """The level changes a primitive comes in: [0], or [0, 1, -1] when it may climb one level."""
    may_climb = p.climb == "all" or (p.climb == "straight" and path.turning < 1e-9)
    if may_climb and path.length * p.max_climb_gradient >= level_gap - 1e-9:
        return [0, 1, -1]
    return [0]


def _edge_groups(p: LatticeParams, grid: _StateGrid, protos: list[_Prototype]) -> list[_Group]:
    """Every edge of the full grid, grouped by (heading, primitive, climb), in a fixed order."""
    ix, iy, iz = grid.cells
    groups: list[_Group] = []
    for k in np.flatnonzero(grid.allowed).tolist():
        cls, quarter = k % 2, k // 2
        for proto_id, proto in enumerate(protos):
            k2 = (k + proto.prim[2]) % NUM_HEADINGS
            if proto.cls != cls or not grid.allowed[k2]:
                continue
            dx, dy = _rotate_cells(proto.prim[0], proto.prim[1], quarter)
            for dl in _climbs(p, proto.path, grid.level_gap):
                tx, ty, tz = ix + dx, iy + dy, iz + dl
                ok = (tx >= 0) & (tx < grid.nx) & (ty >= 0) & (ty < grid.ny) & (tz >= 0) & (tz < grid.nz)
                if not ok.any():
                    continue
                src = grid.state_id(ix[ok], iy[ok], k, iz[ok])
                dst = grid.state_id(tx[ok], ty[ok], k2, tz[ok])
                groups.append(_Group(src, dst, proto_id, dl, quarter))
    if not groups:
        raise ProblemError("the lattice has no edges; check the ranges, spacing and primitives")
    return groups


def _on_start_goal_paths(groups: list[_Group], num_states: int, start: int, goal: int) -> BoolArray:
    """(num_states,) whether each state lies on some start-goal path (forward and backward reachable)."""
    if start == goal:
        raise ProblemError("lattice start and goal are the same state")
    src_all = np.concatenate([g.src for g in groups])
    dst_all = np.concatenate([g.dst for g in groups])
    adjacency = csr_array((np.ones(src_all.size), (src_all, dst_all)), shape=(num_states, num_states), dtype=np.float64)
    forward = np.zeros(num_states, dtype=bool)
    forward[breadth_first_order(adjacency, start, directed=True, return_predecessors=False)] = True
    backward = np.zeros(num_states, dtype=bool)
    backward[breadth_first_order(adjacency.T.tocsr(), goal, directed=True, return_predecessors=False)] = True
    keep = forward & backward
    if not keep[goal]:
        raise ProblemError("the lattice goal is not reachable from the start; widen the ranges or add primitives")
    return np.asarray(keep)


def _kept_edges(groups: list[_Group], keep_state: BoolArray, new_id: IntArray) -> tuple[IntArray, IntArray, IntArray]:
    """(E,) new source ids, target ids and group index of the surviving edges, sorted by (source, target)."""
    edge_src: list[IntArray] = []
    edge_dst: list[IntArray] = []
    edge_group: list[IntArray] = []
    for gi, g in enumerate(groups):
        ok = keep_state[g.src] & keep_state[g.dst]
        edge_src.append(new_id[g.src[ok]])
        edge_dst.append(new_id[g.dst[ok]])
        edge_group.append(np.full(int(ok.sum()), gi, dtype=np.int64))
    u = np.concatenate(edge_src)
    v = np.concatenate(edge_dst)
    grp = np.concatenate(edge_group)
    order = np.lexsort((v, u))
    return u[order], v[order], grp[order]


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


def _group_template(g: _Group, path: DubinsPath, level_gap: float, spacing: float) -> tuple[FloatArray, float]:
    """The (n, 4) samples of a group's edges from the origin, rotated by its quarter turns, and their length."""
    tpl, length = _template(path, g.climb * level_gap if g.climb else 0.0, spacing)
    c, s = math.cos(g.quarter * math.pi / 2), math.sin(g.quarter * math.pi / 2)
    rotated = tpl.copy()
    rotated[:, 0] = c * tpl[:, 0] - s * tpl[:, 1]
    rotated[:, 1] = s * tpl[:, 0] + c * tpl[:, 1]
    rotated[:, 3] = wrap_angle(tpl[:, 3] + g.quarter * math.pi / 2)
    return rotated, length


class _EdgeSamples(NamedTuple):
    """The sampled trajectories of the kept edges and their per-edge attributes."""

    points: FloatArray
    offsets: IntArray
    lengths: FloatArray
    primitive: IntArray
    climb: IntArray


def _edge_samples(
    groups: list[_Group],
    templates: list[tuple[FloatArray, float]],
    states: FloatArray,
    edges: tuple[IntArray, IntArray, IntArray],
) -> _EdgeSamples:
    """Every kept edge's samples: its group's template moved to its source, ends snapped to the states."""
    u, v, grp = edges
    num_edges = u.size
    counts = np.array([templates[g][0].shape[0] for g in grp.tolist()], dtype=np.int64)
    offsets = np.zeros(num_edges + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    out = _EdgeSamples(
        np.empty((int(offsets[-1]), 4), dtype=np.float64),
        offsets,
        np.empty(num_edges, dtype=np.float64),
        np.empty(num_edges, dtype=np.int64),
        np.empty(num_edges, dtype=np.int64),
    )
    for gi, (tpl, length) in enumerate(templates):
        sel = np.flatnonzero(grp == gi)
        if sel.size == 0:
            continue
        base = states[u[sel]]
        idx = offsets[sel][:, None] + np.arange(tpl.shape[0])[None, :]
        block = np.broadcast_to(tpl, (sel.size, *tpl.shape)).copy()
        block[:, :, 0:3] += base[:, None, 0:3]
        out.points[idx.ravel()] = block.reshape(-1, 4)
        out.lengths[sel] = length
        out.primitive[sel] = groups[gi].proto
        out.climb[sel] = groups[gi].climb
    # Snap the end samples to the exact lattice states (removes rounding of the Dubins sampling).
    out.points[offsets[:-1]] = states[u]
    out.points[offsets[1:] - 1] = states[v]
    return out


def build_lattice(params: LatticeParams | None = None) -> HelicopterLattice:
    """Build the pruned lattice graph and all edge trajectories (vectorised over the grid).

    Raises:
        ProblemError: inconsistent parameters (start/goal off the grid, a primitive that needs a loop
            because the turning radius is too large for the spacing), or a goal unreachable from the start.
    """
    p = params or LatticeParams()
    grid = _StateGrid(p)
    protos = _prototypes(p)
    groups = _edge_groups(p, grid, protos)
    start_state = grid.endpoint(p.start, p.level_index(p.start_level), "start")
    goal_state = grid.endpoint(p.goal, p.level_index(p.goal_level), "goal")
    keep_state = _on_start_goal_paths(groups, grid.num_states, start_state, goal_state)
    new_id = np.full(grid.num_states, -1, dtype=np.int64)
    kept_states = np.flatnonzero(keep_state)
    new_id[kept_states] = np.arange(kept_states.size)
    states = grid.states(kept_states)
    u, v, grp = _kept_edges(groups, keep_state, new_id)
    templates = [_group_template(g, protos[g.proto].path, grid.level_gap, p.sample_spacing) for g in groups]
    samples = _edge_samples(groups, templates, states, (u, v, grp))
    graph = ExplicitGraph(
        edges=np.stack([u, v], axis=1),
        lengths=samples.lengths,
        num_vertices=int(kept_states.size),
        directed=True,
        vertex_states=states,
    )
    return HelicopterLattice(
        params=p,
        graph=graph,
        start=int(new_id[start_state]),
        goal=int(new_id[goal_state]),
        points=samples.points,
        offsets=samples.offsets,
        primitive=samples.primitive,
        climb=samples.climb,
        primitive_names=tuple(proto.name for proto in protos),
        primitive_paths=tuple(proto.path for proto in protos),
    )
