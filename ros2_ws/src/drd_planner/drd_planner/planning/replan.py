"""Replan only when needed: after a map update, re-check just the plan edges the update can reach.

A published plan was verified free on the snapshot it was planned on (``old``). When a newer snapshot
(``new``) arrives, :func:`recheck_plan` finds the plan edges the update can reach (:func:`affected_edges`),
checks only those on ``new`` with the domain's FCL checker, stops at the first blocked one and says in one
line what it did (:class:`RecheckResult`). The plan is kept when every re-checked edge is free.

An edge's *sweep spheres* are the spheres its check places (helicopter: the vehicle sphere at every
trajectory sample; arm: every collision sphere, the fixed base spheres included, at both end vertices and
every interior sample at the checker's resolution), each grown by the scene margin and by half the largest
distance it moves between two samples. Its *sweep box* (:func:`edge_sweep_boxes`, metres, planning frame)
is their bounding box. An edge is affected when its box overlaps the AABB of a part that differs between
the snapshots and one of its grown spheres touches that AABB.

**Why an edge that is not re-checked is still free on ``new``** (the safety argument):

1. Both checkers decide an edge from its sampled spheres only, each inflated by the scene margin
   (:class:`~drd_planner.domains.helicopter_checker.HelicopterChecker`,
   :class:`~drd_planner.domains.arm_checker.ArmEdgeChecker`); the domains' sweep models
   (:meth:`~drd_planner.domains.online.OnlineDomain.sweep_spheres`) place the same spheres. A domain whose
   checker tests other shapes (the arm's collision meshes, ``collision_model: meshes``) grows its sweep
   spheres until they contain those shapes, so the argument below holds for them too.
2. The scene (:class:`~drd_planner.geometry.scene.Scene`) decides each sphere against each part on its own
   (an FCL pair test, or "centre inside a closed mesh", both only for parts whose AABB overlaps the
   sphere's AABB) and against the terrain (FCL tiles and "centre under the surface"). Parts do not
   interact, so an edge's outcome depends only on the terrain, the margin and the multiset of parts that
   one of its inflated spheres can touch.
3. A sphere can touch a part only if it touches the part's AABB; the grown spheres contain the checked ones.
4. :func:`differing_parts` treats a change of the terrain, the margin or the arm model
   (``robot_description``) as affecting every edge; otherwise it returns the parts present in only one of
   the two snapshots, compared by value and regardless of their keys (a map re-sent whole, or with
   renumbered markers, but the same geometry is no change), i.e. exactly the difference between the two
   scenes. An
   edge none of whose grown spheres touches one of their AABBs sees the same terrain, margin and relevant
   parts in both snapshots, so its check on ``new`` answers as it did on ``old``: free.

``old`` must therefore be the snapshot the plan was verified on, not merely the previous update: with
several updates in between, the difference between the plan's snapshot and the newest one covers them all.

The growth by half a sample step (every point of the continuous motion between two samples lies within
half the path length between them of one of the two) makes the affected set conservative for the swept
volume of the continuous motion too, not only for the sampled check. Boxes are cached per session in its
:class:`SweepBoxCache` (without the margin, which is added per query) and computed only for the edges asked; the
spheres are recomputed for the few edges whose box overlaps a change. Domains without a sweep model (the planar
ones) count every plan edge as affected.

**Motion edges** (a :class:`~drd_planner.planning.session.QuerySession`'s plans from or to a state
off the graph) have ids from E on that the session maps to the motion's states (``session.motion_states``;
an id names one motion for the session's lifetime, so the box cache stays valid). Their sweep spheres are
those of the motion's own samples (helicopter: the vehicle sphere at each; arm: every collision sphere at
each configuration, grown by half the largest per-joint step between two samples), exactly what the
checkers' ``check_motion`` tests, and a re-check calls ``check_motion`` on them. An id the session does not
know (never planned, or forgotten) is refused with a :class:`PlanningError` (the node then replans): a
motion is never skipped because its geometry is unknown.
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Hashable, Iterable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.domains.base import EdgeChecker
from drd_planner.domains.online import BOX_SLACK, OnlineDomain
from drd_planner.exceptions import PlanningError
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.robot import RobotModel
from drd_planner.geometry.shapes import Shape
from drd_planner.planning.map_state import MapSnapshot, changed_parts, obstacle_boxes

#: Arm models (``robot_description`` versions) whose boxes one session keeps; the oldest is dropped first.
MAX_CACHED_ROBOTS = 4

#: ``(lo, hi)``, each (3,) metres, without margin.
Box = tuple[FloatArray, FloatArray]


class SweepBoxCache:
    """A session's sweep boxes: per arm model (None: the domain's own), edge id -> box without the margin.

    Boxes of at most :data:`MAX_CACHED_ROBOTS` arm models are kept; the oldest model is dropped first.
    """

    def __init__(self) -> None:
        self._boxes: dict[RobotModel | None, dict[int, Box]] = {}

    def boxes(self, robot: RobotModel | None) -> dict[int, Box]:
        """The (mutable) boxes of one arm model, made room for when new."""
        if robot not in self._boxes and len(self._boxes) >= MAX_CACHED_ROBOTS:
            self._boxes.pop(next(iter(self._boxes)))
        return self._boxes.setdefault(robot, {})

    def edges(self, robot: RobotModel | None = None) -> frozenset[int]:
        """Edge ids whose box is kept for an arm model."""
        return frozenset(self._boxes.get(robot, {}))


class ReplanSession(Protocol):
    """What re-checking reads of a session (:class:`~drd_planner.planning.session.QuerySession` has it)."""

    @property
    def name(self) -> str:
        """A label for messages."""
        ...

    @property
    def domain(self) -> OnlineDomain[Any]:
        """The domain (graph, robot or lattice, and its sweep model)."""
        ...

    @property
    def sweep_boxes(self) -> SweepBoxCache:
        """The session's sweep boxes."""
        ...

    @property
    def margin(self) -> float:
        """The domain's collision margin, metres."""
        ...

    def edge_states(self, edge: int) -> FloatArray:
        """(K, D) states along an edge, tail first."""
        ...

    def motion_states(self, edge: int) -> FloatArray | None:
        """(K, D) states of a motion edge id the session knows; None for graph edges and unknown ids."""
        ...

    def checker(self, snapshot: MapSnapshot) -> EdgeChecker:
        """The edge checker of a snapshot."""
        ...


__all__ = [
    "BOX_SLACK",
    "MAX_CACHED_ROBOTS",
    "RecheckResult",
    "ReplanSession",
    "SweepBoxCache",
    "affected_edges",
    "cached_sweep_edges",
    "differing_parts",
    "edge_sweep_boxes",
    "recheck_plan",
]


@dataclass(frozen=True)
class RecheckResult:
    """What re-checking a plan after a map update found.

    Attributes:
        kept: every re-checked edge is free on the new map, so the plan stays valid.
        map_version: version of the new snapshot.
        affected: plan edges (plan order) that the update can reach; ``rechecked`` is a prefix of them.
        rechecked: edges checked on the new snapshot, in order (stops after the first blocked one).
        blocked: the edges found in collision (at most one: checking stops there).
        check_ms: (len(rechecked),) collision-check wall time of each re-check, milliseconds.
        select_ms: time spent finding the affected edges (sweep boxes and overlaps), milliseconds.
        all_edges: every plan edge counted as affected (the terrain, the margin or the arm model changed, or
            the domain has no sweep model).
        reason: one line for logs and ``/diagnostics``.
    """

    kept: bool
    map_version: int
    affected: tuple[int, ...]
    rechecked: tuple[int, ...]
    blocked: tuple[int, ...]
    check_ms: tuple[float, ...]
    select_ms: float
    all_edges: bool
    reason: str

    @property
    def total_check_ms(self) -> float:
        """Sum of :attr:`check_ms`, milliseconds."""
        return float(sum(self.check_ms))


# --------------------------------------------------------------------------------------------------
# Sweep boxes


def _motion_states(session: ReplanSession, edge: int) -> FloatArray | None:
    """(K, D) states of a motion edge the session knows (None: a graph edge, or no such motion)."""
    if edge < session.domain.graph.num_edges:
        return None
    return session.motion_states(edge)


def _edge_ids(session: ReplanSession, edges: Iterable[int]) -> list[int]:
    """``edges`` as a list of ints: graph edges or motions the session knows (PlanningError otherwise)."""
    ids = np.asarray(list(edges)).reshape(-1)
    if ids.size and not np.issubdtype(ids.dtype, np.integer):
        raise PlanningError(f"edge ids must be integers, got dtype {ids.dtype}")
    count = session.domain.graph.num_edges
    out = [int(e) for e in ids.tolist()]
    bad = [e for e in out if not (0 <= e < count or (e >= count and _motion_states(session, e) is not None))]
    if bad:
        raise PlanningError(f"{session.name}: edge ids {bad[:5]} are not in [0, {count}) nor motions the session knows")
    return out


def _sweep_spheres(
    session: ReplanSession, edges: list[int], robot: RobotModel | None
) -> list[tuple[FloatArray, FloatArray]]:
    """Per edge ``(centres (M, 3), reach (M,))`` in metres, without the margin (see the module docstring).

    ``robot`` is the arm model the checker uses (a snapshot's ``robot_description``; None: the domain's).

    Raises:
        PlanningError: the domain has no sweep model.
    """
    domain = session.domain
    if not domain.has_sweep_model:
        raise PlanningError(f"{session.name}: no sweep model for the {domain.name} domain")
    return domain.sweep_spheres(session, edges, robot)


def edge_sweep_boxes(
    session: ReplanSession,
    edges: Iterable[int],
    *,
    margin: float | None = None,
    robot: RobotModel | None = None,
) -> tuple[FloatArray, FloatArray]:
    """``(lo, hi)``, each (N, 3) metres in the planning frame: a conservative box per edge.

    Each box contains every sphere the domain's edge checker places along the edge (helicopter: the
    vehicle sphere at each trajectory sample; arm: every collision sphere at the end vertices and interior
    samples) inflated by ``margin``, plus half the largest motion between two samples (see the module
    docstring). Boxes are cached per session and arm model; only edges not seen before are computed.

    Args:
        session: the planning session (its domain gives the robot model and the sampling).
        edges: (N,) edge ids.
        margin: the scene's collision margin, metres (default: the session's).
        robot: the arm model of the snapshot checked against (``MapSnapshot.robot``; None: the domain's
            own); ignored by the helicopter.

    Raises:
        PlanningError: an edge id neither in the graph nor a motion the session knows, a negative
            margin, or a domain with no sweep model.
    """
    ids = _edge_ids(session, edges)
    pad = session.margin if margin is None else float(margin)
    if not (np.isfinite(pad) and pad >= 0.0):
        raise PlanningError(f"margin must be finite and >= 0 m, got {margin!r}")
    model = session.domain.sweep_robot(robot)
    cache = session.sweep_boxes.boxes(model)
    todo = sorted({e for e in ids if e not in cache})
    if todo:
        for e, (centres, reach) in zip(todo, _sweep_spheres(session, todo, model), strict=True):
            cache[e] = ((centres - reach[:, None]).min(axis=0), (centres + reach[:, None]).max(axis=0))
    if not ids:
        return np.zeros((0, 3)), np.zeros((0, 3))
    lo = np.array([cache[e][0] for e in ids]) - pad
    hi = np.array([cache[e][1] for e in ids]) + pad
    return lo, hi


def cached_sweep_edges(session: ReplanSession, robot: RobotModel | None = None) -> frozenset[int]:
    """Edge ids whose sweep box the session's cache holds for an arm model (for diagnostics and tests)."""
    return session.sweep_boxes.edges(robot)


# --------------------------------------------------------------------------------------------------
# What changed, and which edges it can reach


def _part_key(shape: Shape, pose: Pose) -> Hashable:
    """A value key of a posed part (shapes compare by value; poses by their exact numbers)."""
    return (shape, pose.position.tobytes(), pose.quaternion_xyzw.tobytes())


def differing_parts(old: MapSnapshot, new: MapSnapshot) -> list[tuple[Shape, Pose]] | None:
    """Parts present in only one of two snapshots (by value); None when terrain, margin or arm changed.

    Starts from :func:`~drd_planner.planning.map_state.changed_parts` (per key) and drops parts whose
    exact geometry is in both snapshots under any key: the scene is the union of the parts, so a part that
    only moved to another key (markers renumbered, or an object split into several markers) changes nothing.
    """
    if old.margin != new.margin:
        return None
    parts = changed_parts(old, new)
    if not parts:
        return parts
    keys = [key for key in set(old.obstacles) | set(new.obstacles) if old.obstacles.get(key) != new.obstacles.get(key)]
    before = Counter(_part_key(s, p) for key in keys for s, p in old.obstacles.get(key, ()))
    after = Counter(_part_key(s, p) for key in keys for s, p in new.obstacles.get(key, ()))
    gone, came = before - after, after - before
    out: list[tuple[Shape, Pose]] = []
    for snapshot, wanted in ((new, came), (old, gone)):
        for key in keys:
            for shape, pose in snapshot.obstacles.get(key, ()):
                k = _part_key(shape, pose)
                if wanted[k] > 0:
                    wanted[k] -= 1
                    out.append((shape, pose))
    return out


def _spheres_touch_boxes(
    centres: FloatArray, reach: FloatArray, lo: FloatArray, hi: FloatArray, *, chunk: int = 512
) -> bool:
    """Whether any of the (M, 3) spheres of (M,) radius ``reach`` touches any of the (P, 3) boxes."""
    for start in range(0, centres.shape[0], chunk):
        c = centres[start : start + chunk, None, :]
        gap = np.maximum(lo[None] - c, 0.0) + np.maximum(c - hi[None], 0.0)  # per axis, 0 inside
        limit = reach[start : start + chunk, None] ** 2
        if bool((np.einsum("mpi,mpi->mp", gap, gap) <= limit).any()):
            return True
    return False


def _affected(
    session: ReplanSession,
    plan_edges: Sequence[int],
    old: MapSnapshot,
    new: MapSnapshot,
    *,
    refine: bool,
) -> tuple[tuple[int, ...], str]:
    """(affected edges in plan order, why every edge counts as affected or "" when only some do)."""
    ordered = tuple(dict.fromkeys(_edge_ids(session, plan_edges)))
    parts = differing_parts(old, new)
    if parts is None:
        return ordered, "terrain, margin or arm model changed"
    if not parts or not ordered:
        return (), ""
    if not session.domain.has_sweep_model:
        return ordered, f"no sweep model for the {session.domain.name} domain"
    part_lo, part_hi = obstacle_boxes(parts)
    lo, hi = edge_sweep_boxes(session, ordered, margin=new.margin, robot=new.robot)
    near = np.all((lo[:, None, :] <= part_hi[None]) & (hi[:, None, :] >= part_lo[None]), axis=2)
    candidates = [i for i in range(len(ordered)) if near[i].any()]
    if not refine or not candidates:
        return tuple(ordered[i] for i in candidates), ""
    spheres = _sweep_spheres(session, [ordered[i] for i in candidates], session.domain.sweep_robot(new.robot))
    hits = [
        ordered[i]
        for i, (centres, reach) in zip(candidates, spheres, strict=True)
        if _spheres_touch_boxes(centres, reach + new.margin, part_lo[near[i]], part_hi[near[i]])
    ]
    return tuple(hits), ""


def affected_edges(
    session: ReplanSession,
    plan_edges: Sequence[int],
    old_snapshot: MapSnapshot,
    new_snapshot: MapSnapshot,
    *,
    refine: bool = True,
) -> tuple[int, ...]:
    """Plan edges (plan order, each once) whose check on ``new_snapshot`` may differ from ``old_snapshot``.

    An edge is affected when its sweep box (:func:`edge_sweep_boxes` with the new snapshot's margin)
    overlaps the AABB of a part that appeared, moved or disappeared (:func:`differing_parts`) and, with
    ``refine``, one of its grown spheres (the sweep box is their bounding box) touches that AABB too. A
    changed terrain or margin, or a domain without a sweep model, affects every edge.

    Args:
        session: the session the plan came from.
        plan_edges: the plan's edge ids.
        old_snapshot: the snapshot the plan was verified on.
        new_snapshot: the latest snapshot.
        refine: also test the spheres of the edges whose box overlaps a change (False: the box test only).

    Raises:
        PlanningError: an edge id neither in the graph nor a motion the session knows.
    """
    return _affected(session, plan_edges, old_snapshot, new_snapshot, refine=refine)[0]


# --------------------------------------------------------------------------------------------------
# Re-checking


def _recheck_one(session: ReplanSession, checker: EdgeChecker, edge: int) -> bool:
    """Check one plan edge on the new snapshot: a graph edge by id, a motion through ``check_motion``."""
    motion = _motion_states(session, edge)
    if motion is None:
        return bool(checker.check(edge))
    check_motion = getattr(checker, "check_motion", None)
    if check_motion is None:
        raise PlanningError(f"{session.name}: the checker cannot re-check motion edge {edge}")
    return bool(check_motion(motion))


def recheck_plan(
    session: ReplanSession,
    plan_edges: Sequence[int],
    old_snapshot: MapSnapshot,
    new_snapshot: MapSnapshot,
    *,
    checker: EdgeChecker | None = None,
) -> RecheckResult:
    """Re-check on ``new_snapshot`` only the plan edges the update can reach; stop at the first blocked.

    Args:
        session: the session the plan came from.
        plan_edges: the plan's edge ids, in order (graph edges, and motion ids the session knows).
        old_snapshot: the snapshot the plan was verified on (see the module docstring).
        new_snapshot: the latest snapshot.
        checker: the edge checker of ``new_snapshot`` (default ``session.checker(new_snapshot)``, built
            only when some edge needs a check).

    Raises:
        PlanningError: an edge id neither in the graph nor a motion the session knows.
    """
    t0 = time.perf_counter()
    affected, everything = _affected(session, plan_edges, old_snapshot, new_snapshot, refine=True)
    select_ms = (time.perf_counter() - t0) * 1e3
    rechecked: list[int] = []
    check_ms: list[float] = []
    blocked: list[int] = []
    if affected:
        check = checker if checker is not None else session.checker(new_snapshot)
        for e in affected:
            t1 = time.perf_counter()
            free = _recheck_one(session, check, e)
            check_ms.append((time.perf_counter() - t1) * 1e3)
            rechecked.append(e)
            if not free:
                blocked.append(e)
                break
    total = len(dict.fromkeys(int(e) for e in plan_edges))
    version = f"map v{new_snapshot.version}"
    if blocked:
        why = f" ({everything})" if everything else ""
        reason = (
            f"{version}: plan edge {blocked[0]} blocked by the update{why}, "
            f"{len(rechecked)} of {len(affected)} affected edges re-checked; replanning"
        )
    elif everything:
        reason = f"{version}: {everything}; all {total} plan edges re-checked free; plan kept"
    elif affected:
        reason = f"{version}: {len(affected)} of {total} plan edges near changed obstacles re-checked free; plan kept"
    else:
        reason = f"{version}: no plan edge near the changed obstacles; plan kept without checks"
    return RecheckResult(
        kept=not blocked,
        map_version=new_snapshot.version,
        affected=affected,
        rechecked=tuple(rechecked),
        blocked=tuple(blocked),
        check_ms=tuple(check_ms),
        select_ms=select_ms,
        all_edges=bool(everything),
        reason=reason,
    )
