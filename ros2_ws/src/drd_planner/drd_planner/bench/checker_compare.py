"""Two collision models of the arm compared edge by edge on the same roadmap and worlds.

:func:`compare_world` checks every roadmap edge of one world with a sphere-model and a mesh-model checker
(:meth:`~drd_planner.domains.arm.ArmDomain.checker` of two domains that differ only in ``collision_model``),
one edge after the other with both (so machine load hits both alike), timing every ``check`` call. Edges the
meshes find blocked but the spheres call free are where the sphere model does not cover the robot; for each
it records where (:class:`Miss`): the first blocked sample in check order, the mesh element's link, the
obstacle, how deep the mesh goes into it (FCL's deepest contact) and how far the spheres stay from that
obstacle at that sample.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import fcl
import numpy as np

from drd_planner.arrays import BoolArray, FloatArray
from drd_planner.bench.world_recipes import WorldRecipe
from drd_planner.domains.arm import ArmDomain
from drd_planner.domains.arm_checker import ArmEdgeChecker
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.fcl_queries import pair_distance
from drd_planner.geometry.mesh_collider import MeshCollider, MeshContact

__all__ = ["Miss", "WorldComparison", "compare_world", "summarize"]


@dataclass(frozen=True)
class Miss:
    """An edge the meshes find blocked and the spheres free, and where.

    Attributes:
        world: the world's label.
        edge: the edge id.
        sample: the first blocked configuration in check order: 0 and 1 the end vertices, k >= 2 the
            (k - 2)-th interior sample in bisection order; -1 for the robot's base (every configuration).
        vertex: the roadmap vertex of samples 0 and 1, else -1.
        fraction: where that sample lies along the edge (0 at its first vertex, 1 at its second).
        link: the mesh element's link.
        obstacle: the obstacle's name (empty when not known).
        reason: how the mesh is blocked (:class:`~drd_planner.geometry.mesh_collider.MeshContact`).
        depth_m: the deepest FCL contact of the mesh into the obstacle (m).
        sphere_clearance_m: the smallest distance from a robot sphere to that obstacle there (m; NaN when
            the obstacle is not known).
        point: where the deepest contact is, in the link's frame (m; NaN unless ``reason`` is ``contact``).
    """

    world: str
    edge: int
    sample: int
    vertex: int
    fraction: float
    link: str
    obstacle: str
    reason: str
    depth_m: float
    sphere_clearance_m: float
    point: tuple[float, float, float] = (float("nan"),) * 3


@dataclass
class WorldComparison:
    """One world's edges under both models.

    Attributes:
        recipe: the world.
        free_spheres: (E,) the sphere checker's outcomes (True = free).
        free_meshes: (E,) the mesh checker's outcomes.
        ms_spheres: (E,) time of each sphere ``check`` (ms, fresh checker, edges in id order).
        ms_meshes: (E,) time of each mesh ``check`` (ms).
        misses: the edges free for the spheres and blocked for the meshes, with where.
    """

    recipe: WorldRecipe
    free_spheres: BoolArray
    free_meshes: BoolArray
    ms_spheres: FloatArray
    ms_meshes: FloatArray
    misses: list[Miss] = field(default_factory=list)

    @property
    def spheres_only_blocked(self) -> int:
        """Edges blocked for the spheres and free for the meshes (the conservative direction)."""
        return int(np.sum(~self.free_spheres & self.free_meshes))

    @property
    def meshes_only_blocked(self) -> int:
        """Edges blocked for the meshes and free for the spheres (the spheres miss the robot)."""
        return int(np.sum(self.free_spheres & ~self.free_meshes))


def _mesh_model(checker: ArmEdgeChecker) -> MeshCollider:
    """The checker's mesh collision model, or ProblemError."""
    if not isinstance(checker.model, MeshCollider):
        raise ProblemError("the second domain must have collision_model 'meshes'")
    return checker.model


def _sphere_clearance(domain: ArmDomain, q: FloatArray, obstacle: fcl.CollisionObject) -> float:
    """Smallest distance (m) from any robot sphere at (D,) ``q`` to ``obstacle`` (<= 0: touching)."""
    robot = domain.robot
    centres = robot.sphere_centres(q[None])[0]
    best = np.inf
    for centre, radius in zip(centres, robot.spheres.radii.tolist(), strict=True):
        ball = fcl.CollisionObject(fcl.Sphere(radius), fcl.Transform(centre))
        best = min(best, pair_distance(ball, obstacle))
    return float(best)


def _explain(domain: ArmDomain, checker: ArmEdgeChecker, recipe: WorldRecipe, names: Sequence[str], edge: int) -> Miss:
    """Where the mesh checker blocks ``edge`` (see :class:`Miss`)."""
    model = _mesh_model(checker)
    states = checker.graph.vertex_states
    assert states is not None
    u, v = (int(x) for x in checker.graph.edges[edge])
    interior = checker.samples.configurations(checker.graph, edge)
    q = np.concatenate([states[[u, v]], interior])
    fractions = np.concatenate(
        [
            [0.0, 1.0],
            checker.samples.fractions[checker.samples.offsets[edge] : checker.samples.offsets[edge + 1]],
        ]
    )
    contact: MeshContact | None = model.base_contact() if not model.base_free() else model.first_contact(q)
    if contact is None:  # self-collision (another robot model) or a model disagreeing with itself
        return Miss(recipe.label, edge, -1, -1, float("nan"), "", "", "unexplained", 0.0, float("nan"))
    base = not model.base_free()
    obstacle = names[contact.obstacle] if 0 <= contact.obstacle < len(names) else ""
    clearance = float("nan")
    if 0 <= contact.obstacle < len(model.obstacles.objects):
        clearance = _sphere_clearance(domain, q[0 if base else contact.row], model.obstacles.objects[contact.obstacle])
    return Miss(
        recipe.label,
        edge,
        -1 if base else contact.row,
        (u, v)[contact.row] if not base and contact.row < 2 else -1,
        float("nan") if base else float(fractions[contact.row]),
        contact.link,
        obstacle,
        contact.reason,
        contact.depth,
        clearance,
        (float(contact.point[0]), float(contact.point[1]), float(contact.point[2])),
    )


def compare_world(
    spheres: ArmDomain, meshes: ArmDomain, recipe: WorldRecipe, edges: Sequence[int] | None = None
) -> WorldComparison:
    """Check ``edges`` (all when None) of one world with both models, timing each check.

    Args:
        spheres: the domain with ``collision_model: spheres``.
        meshes: the same domain with ``collision_model: meshes`` (same roadmap).
        recipe: the world (made with ``spheres``).
        edges: edge ids, checked in this order.

    Raises:
        ProblemError: the two domains' roadmaps differ, or ``meshes`` is not a mesh domain.
    """
    if not np.array_equal(spheres.graph.edges, meshes.graph.edges):
        raise ProblemError("the sphere and mesh domains must share one roadmap")
    world = recipe.make(spheres)
    ids = np.arange(spheres.graph.num_edges) if edges is None else np.asarray(edges, dtype=np.int64)
    by_spheres, by_meshes = spheres.checker(world), meshes.checker(world)
    _mesh_model(by_meshes)
    free = np.zeros((2, ids.size), dtype=bool)
    ms = np.zeros((2, ids.size))
    for i, e in enumerate(ids.tolist()):
        free[0, i], ms[0, i] = _timed_check(by_spheres, e)
        free[1, i], ms[1, i] = _timed_check(by_meshes, e)
    names = [o.name for o in world.obstacles]
    misses = [_explain(meshes, by_meshes, recipe, names, int(ids[i])) for i in np.nonzero(free[0] & ~free[1])[0]]
    return WorldComparison(recipe, free[0], free[1], ms[0], ms[1], misses)


def _timed_check(checker: ArmEdgeChecker, edge: int) -> tuple[bool, float]:
    """``(free, ms)``: one ``check`` call and its time."""
    t0 = time.perf_counter()
    free = checker.check(edge)
    return free, 1e3 * (time.perf_counter() - t0)


def summarize(results: Sequence[WorldComparison]) -> dict[str, Any]:
    """Per family and overall: edges, agreement, both directions of disagreement, times, misses by link.

    Returns:
        ``{"families": {family: {...}}, "all": {...}, "misses_by_link": {link: {...}}}``; every block has
        ``worlds``, ``edges``, ``free_spheres``, ``free_meshes``, ``agree``, ``spheres_only_blocked``,
        ``meshes_only_blocked`` (counts), ``ms_spheres_mean``, ``ms_meshes_mean``, ``ms_spheres_median``,
        ``ms_meshes_median`` and ``time_ratio`` (mesh / sphere mean time per edge); per link of the misses:
        ``edges``, ``at_end_vertex``, ``distinct_vertices`` (different (world, vertex) pairs among those),
        depth, sphere clearance and the median contact point in the link frame.
    """
    families: dict[str, list[WorldComparison]] = {}
    for r in results:
        families.setdefault(r.recipe.family, []).append(r)
    out: dict[str, Any] = {"families": {k: _block(v) for k, v in families.items()}, "all": _block(results)}
    links: dict[str, list[Miss]] = {}
    for r in results:
        for m in r.misses:
            links.setdefault(m.link, []).append(m)
    out["misses_by_link"] = {
        link: {
            "edges": len(ms),
            "at_end_vertex": sum(m.sample in (0, 1) for m in ms),
            "distinct_vertices": len({(m.world, m.vertex) for m in ms if m.vertex >= 0}),
            "depth_mm_median": 1e3 * float(np.median([m.depth_m for m in ms])),
            "depth_mm_max": 1e3 * float(np.max([m.depth_m for m in ms])),
            "point_median_m": [float(x) for x in np.round(np.nanmedian([m.point for m in ms], axis=0), 3)]
            if any(np.isfinite(m.point[0]) for m in ms)
            else [float("nan")] * 3,
            "sphere_clearance_mm_median": 1e3 * float(np.nanmedian([m.sphere_clearance_m for m in ms]))
            if any(np.isfinite(m.sphere_clearance_m) for m in ms)
            else float("nan"),
        }
        for link, ms in sorted(links.items(), key=lambda item: -len(item[1]))
    }
    return out


def _block(results: Sequence[WorldComparison]) -> dict[str, Any]:
    """The summary numbers of a group of worlds."""
    fs = np.concatenate([r.free_spheres for r in results]) if results else np.zeros(0, dtype=bool)
    fm = np.concatenate([r.free_meshes for r in results]) if results else np.zeros(0, dtype=bool)
    ts = np.concatenate([r.ms_spheres for r in results]) if results else np.zeros(0)
    tm = np.concatenate([r.ms_meshes for r in results]) if results else np.zeros(0)
    mean_s, mean_m = (float(t.mean()) if t.size else float("nan") for t in (ts, tm))
    return {
        "worlds": len(results),
        "edges": int(fs.size),
        "free_spheres": int(fs.sum()),
        "free_meshes": int(fm.sum()),
        "agree": int(np.sum(fs == fm)),
        "spheres_only_blocked": int(np.sum(~fs & fm)),
        "meshes_only_blocked": int(np.sum(fs & ~fm)),
        "ms_spheres_mean": mean_s,
        "ms_meshes_mean": mean_m,
        "ms_spheres_median": float(np.median(ts)) if ts.size else float("nan"),
        "ms_meshes_median": float(np.median(tm)) if tm.size else float("nan"),
        "time_ratio": mean_m / mean_s if mean_s > 0 else float("nan"),
    }
