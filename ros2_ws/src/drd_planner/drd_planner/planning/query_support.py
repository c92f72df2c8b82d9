"""Helpers of :class:`~drd_planner.planning.query_session.QuerySession`.

Poses to states, session-wide motion ids, dense paths, the snapshot oracle and the domain rebuild.

**Motion edge ids.** The :class:`~drd_planner.planner.Planner` numbers the new motions of each query from E
on, so the same id names different motions in different queries. A session that keeps published plans
(and re-checks them after a map update) needs ids that name one motion only: :class:`MotionRegistry` gives
every distinct motion (by its exact states) a session-wide id from E on, the same id while the motion is
remembered, and never reuses an id, so a forgotten motion is unknown rather than mistaken for another.
"""

from __future__ import annotations

import math
import time
from collections import OrderedDict
from collections.abc import Callable
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.domains.base import EdgeChecker
from drd_planner.domains.online import OnlineDomain
from drd_planner.domains.pose_states import wrap_angle
from drd_planner.exceptions import PlanningError, PriorFileError, UnverifiedPathError
from drd_planner.planner.prior import WorldPrior
from drd_planner.planning.cancel import CancelToken
from drd_planner.planning.domain_view import domain_from_stored_spec

#: Motions a session remembers (for ``edge_states`` and re-checks of published plans); oldest dropped first.
DEFAULT_MOTIONS_KEPT = 1024
#: How far (state units) consecutive pieces of a dense path may be apart where they meet.
JOIN_TOLERANCE = 1e-6


def yaw_from_quaternion(xyzw: npt.ArrayLike) -> float:
    """The yaw (rad, about +z, in [-pi, pi)) of an (x, y, z, w) quaternion (need not be normalised).

    Raises:
        PlanningError: not four finite numbers, or a zero quaternion.
    """
    q = np.asarray(xyzw, dtype=np.float64).ravel()
    if q.shape != (4,) or not np.all(np.isfinite(q)) or not np.any(q):
        raise PlanningError(f"an orientation must be a finite non-zero (x, y, z, w) quaternion, got {q.tolist()}")
    x, y, z, w = q / np.linalg.norm(q)
    return wrap_angle(math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)))


class MotionRegistry:
    """Session-wide ids of motions (see the module docstring).

    Args:
        first_id: the first id given (the graph's edge count E).
        capacity: motions remembered; the least recently used is forgotten first.
    """

    def __init__(self, first_id: int, *, capacity: int = DEFAULT_MOTIONS_KEPT) -> None:
        if capacity < 1:
            raise PlanningError(f"a session must remember at least one motion, got {capacity}")
        self._first = int(first_id)
        self._next = int(first_id)
        self._capacity = int(capacity)
        self._ids: OrderedDict[bytes, int] = OrderedDict()
        self._states: dict[int, FloatArray] = {}

    def __len__(self) -> int:
        return len(self._states)

    def id_for(self, states: npt.ArrayLike) -> int:
        """The id of the motion through the (K, D) ``states`` (registered now if new)."""
        array = np.array(states, dtype=np.float64)
        key = array.shape[1:].__repr__().encode() + array.tobytes()
        known = self._ids.get(key)
        if known is not None:
            self._ids.move_to_end(key)
            return known
        motion = self._next
        self._next += 1
        array.setflags(write=False)
        self._ids[key] = motion
        self._states[motion] = array
        while len(self._ids) > self._capacity:
            _, dropped = self._ids.popitem(last=False)
            del self._states[dropped]
        return motion

    def states(self, motion: int) -> FloatArray | None:
        """(K, D) states of a remembered motion id, tail first (None: not a motion id, or forgotten)."""
        return self._states.get(int(motion))

    def is_motion_id(self, edge: int) -> bool:
        """Whether ``edge`` is in the range of ids this registry has given (remembered or not)."""
        return self._first <= int(edge) < self._next


def join_pieces(pieces: list[FloatArray], *, dim: int, periodic: tuple[int, ...] = ()) -> FloatArray:
    """(K, dim) states of consecutive path pieces (each oriented in traversal order), shared states once.

    ``periodic`` names angle dimensions (rad), compared modulo 2 pi where pieces meet.

    Raises:
        UnverifiedPathError: two consecutive pieces do not meet (the path's bookkeeping is broken).
    """
    if not pieces:
        return np.zeros((0, dim))
    for k in range(1, len(pieces)):
        head, tail = pieces[k - 1][-1], pieces[k][0]
        diff = np.abs(tail - head)
        for d in periodic:
            diff[d] = abs(wrap_angle(float(tail[d] - head[d])))
        gap = float(np.max(diff))
        if not gap <= JOIN_TOLERANCE * max(1.0, float(np.max(np.abs(head)))):
            raise UnverifiedPathError(f"path pieces {k - 1} and {k} do not meet (gap {gap:.3g})")
    return np.concatenate([pieces[0]] + [p[1:] for p in pieces[1:]])


class SnapshotOracle:
    """An edge and motion oracle on one snapshot's checker, with that snapshot's outcome cache.

    Graph edges are cached by id, motions by their :class:`MotionRegistry` id (the cache may hold both:
    motion ids start at E). ``timings`` and ``motion_calls`` record what this oracle was asked.
    """

    def __init__(
        self,
        checker: EdgeChecker,
        cache: dict[int, bool],
        motions: MotionRegistry,
        cancel: CancelToken | None = None,
    ) -> None:
        self._checker = checker
        self._cache = cache
        self._motions = motions
        self._cancel = cancel  # read before every answer: a cancelled plan stops before its next check
        self.timings: dict[int, tuple[float, bool]] = {}  # session edge id -> (check ms, cached)
        self.motion_calls: list[int] = []  # session motion ids, in the order they were checked

    def _answer(self, key: int, run: Callable[[], bool]) -> bool:
        if self._cancel is not None:
            self._cancel.check(len(self.timings))  # PlanCancelled once the requester cancelled
        known = self._cache.get(key)
        if known is not None:
            self.timings[key] = (0.0, True)
            return known
        t0 = time.perf_counter()
        free = bool(run())
        self.timings[key] = ((time.perf_counter() - t0) * 1e3, False)
        self._cache[key] = free
        return free

    def check(self, edge: int) -> bool:
        """True when graph edge ``edge`` is free (from the cache, or the checker)."""
        e = int(edge)
        return self._answer(e, lambda: self._checker.check(e))

    def check_motion(self, states: FloatArray) -> bool:
        """True when the motion through (K, D) ``states`` is free (from the cache, or the checker)."""
        motion = self._motions.id_for(states)
        self.motion_calls.append(motion)
        check_motion = getattr(self._checker, "check_motion", None)
        if check_motion is None:
            raise PlanningError("this domain's checker cannot check motions off the graph")
        return self._answer(motion, lambda: bool(check_motion(states)))

    def explain_motion(self, states: FloatArray) -> str:
        """What blocks the motion through (K, D) ``states`` ("" when free), for the reason of a failed plan.

        The checker's own ``explain_motion`` when it has one (:class:`~drd_planner.planner.connect.MotionExplainer`),
        else ``"blocked"`` or "" from its ``check_motion``. Neither the cache nor the plan's check log sees it.
        """
        explain = getattr(self._checker, "explain_motion", None)
        if explain is not None:
            return str(explain(states))
        check_motion = getattr(self._checker, "check_motion", None)
        if check_motion is None:
            raise PlanningError("this domain's checker cannot check motions off the graph")
        return "" if check_motion(states) else "blocked"


def rebuild_domain(prior: WorldPrior, name: str) -> OnlineDomain[Any]:
    """The prior's domain rebuilt from its stored spec, after checking it builds the prior's graph.

    Raises:
        PriorFileError: no domain spec, a spec that cannot be rebuilt (any exception), or a graph that
            differs from the stored one.
    """
    if not prior.domain_spec:
        raise PriorFileError(f"{name}: the prior has no domain spec (built from an authors' dataset?)")
    domain = domain_from_stored_spec(prior.domain, prior.domain_spec, label=name, error=PriorFileError)
    if not same_graph(domain, prior):
        raise PriorFileError(f"{name}: the stored graph does not match the graph of its domain spec")
    return domain


def same_graph(domain: OnlineDomain[Any], prior: WorldPrior) -> bool:
    """Whether the domain's graph is the prior's (edges, lengths, direction and vertex states)."""
    ours, theirs = domain.graph, prior.graph
    if (
        ours.edges.shape != theirs.edges.shape
        or not np.array_equal(ours.edges, theirs.edges)
        or not np.allclose(ours.lengths, theirs.lengths)
        or bool(ours.directed) != bool(theirs.directed)
    ):
        return False
    a, b = ours.vertex_states, theirs.vertex_states
    if a is None or b is None:
        return a is None and b is None
    return bool(a.shape == b.shape and np.allclose(a, b))
