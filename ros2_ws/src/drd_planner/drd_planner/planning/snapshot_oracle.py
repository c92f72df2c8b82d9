"""The edge and motion oracle of one plan: a map snapshot's checker, with that snapshot's outcome cache."""

from __future__ import annotations

import time
from collections.abc import Callable

from drd_planner.arrays import FloatArray
from drd_planner.domains.base import EdgeChecker
from drd_planner.exceptions import PlanningError
from drd_planner.planning.cancel import CancelToken
from drd_planner.planning.session_motions import MotionRegistry

__all__ = ["SnapshotOracle"]


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
