"""What a planning session returns for one request on one map snapshot: :class:`SessionPlan` and its checks.

The planner's :class:`~drd_planner.planner.result.PlanResult` speaks in the ids of the query's own graph;
a :class:`SessionPlan` is the same plan as the online side hands it out: the map version it was planned on,
the prior that planned it, the check log in the session's edge ids (motions included, each check's wall
time and whether it came from the snapshot's cache), and the path's dense states, re-verified by the
session (:class:`~drd_planner.planning.session.QuerySession`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.core.status import PlanCause, PlanStatus

__all__ = ["SessionCheck", "SessionPlan"]


@dataclass(frozen=True)
class SessionCheck:
    """One check of a plan.

    Attributes:
        step: 1-based order.
        edge: edge id (a motion id, >= E, for a motion off the graph); ``endpoints`` its (u, v) vertices.
        free: outcome.
        stage: which stage chose it (``tree``, ``bisect``, ``graph``, ``grow``, ``improve``, ...).
        check_ms: collision-check wall time, ms (0 when answered from the cache).
        select_ms: time the policy took to choose the edge, ms.
        cached: answered from the cache of this map snapshot.
    """

    step: int
    edge: int
    endpoints: tuple[int, int]
    free: bool
    stage: str
    check_ms: float
    select_ms: float
    cached: bool


@dataclass(frozen=True)
class SessionPlan:
    """The outcome of one request served by a session on one map snapshot.

    ``path_edges`` may hold motion ids (>= E, see :meth:`QuerySession.edge_states
    <drd_planner.planning.session.QuerySession.edge_states>`); ``path_vertices`` ids >= V name the query's own
    start or goal state (or a vertex roadmap growth added).

    Attributes:
        status: how it ended, in the planner's words: FOUND (a path was proven free; :attr:`ok`), NO_PATH,
            BUDGET_EXHAUSTED (``cause`` says which budget) or REFUSED (a start or goal the prior cannot serve).
        message: one line for logs and diagnostics.
        map_version: the snapshot planned on.
        prior: name of the prior that planned it (its file stem; a tree file loads as a prior).
        path_edges: edge ids of the path, in order (empty unless ok).
        path_vertices: its vertex ids (start ... goal).
        states: (K, D) the path's states (trajectory samples; x, y, z metres first, or joint angles).
        checks: every check, in order.
        seconds: wall times in seconds: ``prepare`` (the snapshot's FCL scene and checker, when
            :meth:`~drd_planner.planning.session.QuerySession.prepare` had not built them already), ``checks``
            (in FCL), ``selection`` (the policy choosing edges), ``library`` (finding or building the query's
            library and tree), ``policy`` (the planner's time less library and checks), ``total``.
        cause: why it failed, where the planner can tell (:class:`~drd_planner.core.status.PlanCause`: the start
            or goal outside or walled in, or the budget that ran out); None otherwise, and when FOUND.
        stage: which stage proved the path (``tree``, ``bisect``, ``library``, ``graph``, ``trivial``, or
            ``improve`` when the anytime improvement found a shorter one; "" unless ok).
        query: ``tree:<name>`` (a precomputed tree), ``online`` or ``connected`` (with new motions).
        query_cached: the query's library and tree came from the planner's query cache (an earlier
            request of the same query built them).
        cost: the path's length in the domain's unit (0 unless ok).
        library_size: paths in the query's library.
        first_cost: with an improve budget, the cost of the plan's first verified path (0 otherwise).
        improvements: with an improve budget, how many shorter verified paths were found after the first.
        improve_stop: with an improve budget, why the improvement stopped (``optimal``, ``checks``,
            ``seconds``, ``patience``, ``plan_checks``, ``plan_time``); "" without one or unless ok.
    """

    status: PlanStatus
    message: str
    map_version: int
    prior: str
    path_edges: tuple[int, ...] = ()
    path_vertices: tuple[int, ...] = ()
    states: FloatArray = field(default_factory=lambda: np.zeros((0, 3)))
    checks: tuple[SessionCheck, ...] = ()
    seconds: dict[str, float] = field(default_factory=dict)
    cause: PlanCause | None = None
    stage: str = ""
    query: str = ""
    query_cached: bool = False
    cost: float = 0.0
    library_size: int = 0
    first_cost: float = 0.0
    improvements: int = 0
    improve_stop: str = ""

    @property
    def ok(self) -> bool:
        """A path was proven free (status FOUND)."""
        return self.status is PlanStatus.FOUND

    @property
    def outcome(self) -> str:
        """The status's value, and the cause's after a colon when there is one (``budget_exhausted: check_budget``).

        What log lines, ``drd plan`` and the heartbeat's ``last_plan`` show.
        """
        return self.status.value if self.cause is None else f"{self.status.value}: {self.cause.value}"

    @property
    def tree(self) -> str:
        """Deprecated alias of :attr:`prior` (read-only; removed in the next release)."""
        return self.prior

    @property
    def num_blocked(self) -> int:
        """Checks that found the edge in collision."""
        return sum(not c.free for c in self.checks)
