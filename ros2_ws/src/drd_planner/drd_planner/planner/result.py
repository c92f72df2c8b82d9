"""What :meth:`drd_planner.planner.Planner.plan` returns: status, verified path, check log, timings.

The status (:class:`~drd_planner.core.status.PlanStatus`) and cause (:class:`~drd_planner.core.status.PlanCause`)
enums live at the core's floor (the episode runner speaks them too); ``PlanStatus`` is re-exported here.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import Enum
from typing import TYPE_CHECKING

import numpy as np

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.core.episode import CheckRecord
from drd_planner.core.status import PlanCause, PlanStatus
from drd_planner.exceptions import PlanningError
from drd_planner.planner.query_library import vertex_sequence

__all__ = [
    "GrowthReport",
    "Improvement",
    "PlanResult",
    "PlanStage",
    "PlanStatus",
    "PlanTimings",
    "exhausted_result",
    "found_result",
    "library_stage",
    "plan_timings",
    "trivial_result",
    "unproven_result",
]

if TYPE_CHECKING:
    from drd_planner.planner.query_graph import QueryGraph
    from drd_planner.planner.query_model import QueryModel


class PlanStage(str, Enum):
    """Which stage proved the path."""

    #: The probe: a new query's union path, checked before its library is built (:mod:`drd_planner.planner.probe`).
    PROBE = "probe"
    #: The lead: a new query's lazy search before its library, for as many checks as the library costs
    #: (:mod:`drd_planner.planner.lead`; only when the planner is told what a check costs).
    LEAD = "lead"
    #: The DiRECt tree (precomputed, or grown online for a new query).
    TREE = "tree"
    #: BiSECt on the query's path library (after the tree).
    BISECT = "bisect"
    #: Another library policy (a baseline chosen with ``policy=``).
    LIBRARY = "library"
    #: The search over the whole graph once every library path was blocked.
    GRAPH = "graph"
    #: The search over the graph grown with new vertices and edges (:mod:`drd_planner.planner.roadmap_growth`).
    GROW = "grow"
    #: Start and goal are the same vertex: the empty path, nothing to check.
    TRIVIAL = "trivial"
    #: The anytime improvement after the first verified path (:mod:`drd_planner.planner.anytime`).
    IMPROVE = "improve"


@dataclass(frozen=True)
class Improvement:
    """One verified path of a plan that went on improving (the first path first, then each shorter one).

    Attributes:
        checks_so_far: the plan's checks when this path was verified (the first path's own count first).
        path_edges: (L,) int64 edge ids of the path, start to goal; every one was checked free in this plan.
        cost: the path's length (the graph's edge lengths summed), in the domain's unit.
        elapsed_s: seconds from the start of the plan to its verification.
    """

    checks_so_far: int
    path_edges: IntArray
    cost: float
    elapsed_s: float


@dataclass(frozen=True)
class GrowthReport:
    """What roadmap growth did in one plan (:mod:`drd_planner.planner.roadmap_growth`).

    Attributes:
        rounds: growth rounds run (count).
        vertices_added: new vertices (statically valid states) in the query's graph (count).
        edges_added: new edges (motions between them and their neighbours) (count).
        checks: checks made after growth began (new edges and old ones alike, new vertices included).
        stop: why it stopped: ``path`` (a path was verified), ``start_blocked``, ``goal_blocked`` (that
            state itself is blocked: no path can exist; growth checks both first), ``rounds``, ``vertices``,
            ``seconds``, ``checks`` (a growth budget), ``plan_checks``, ``plan_time`` (the plan's own budgets),
            ``exhausted`` (nothing more to add: every flyable motion joining the start and goal was tried).
        query: the grown query: its graph (vertex states included; new vertices from the query's V on, new
            edges from its E on), training columns (new edges' imputed) and every motion edge (the query's
            joins and the grown edges, edge id -> (K, D) states, tail first).
        state_checks: of ``checks``, those of one state: the start's and the goal's, then each new vertex's
            before it is joined (the one-state motion of its vertex edge, a self-loop;
            :mod:`~drd_planner.planner.grown_graph`).
    """

    rounds: int
    vertices_added: int
    edges_added: int
    checks: int
    stop: str
    query: QueryGraph
    state_checks: int = 0

    def summary(self) -> str:
        """E.g. ``3 growth round(s) added 150 vertices and 900 edges (420 checks, 152 of one state; stopped: path)``."""
        return (
            f"{self.rounds} growth round(s) added {self.vertices_added} vertices and {self.edges_added} edges "
            f"({self.checks} checks, {self.state_checks} of them of one state; stopped: {self.stop})"
        )


@dataclass(frozen=True)
class PlanTimings:
    """Where a plan's time went, in seconds.

    Attributes:
        library_s: finding or building the query's library (and its DiRECt tree) for this query.
        selection_s: choosing edges (the policy's selection, updates between checks not included).
        checks_s: inside the oracle's ``check``.
        total_s: the whole call.
    """

    library_s: float = 0.0
    selection_s: float = 0.0
    checks_s: float = 0.0
    total_s: float = 0.0

    @property
    def other_s(self) -> float:
        """Everything else: the policies' updates after each outcome and bookkeeping."""
        return max(self.total_s - self.library_s - self.selection_s - self.checks_s, 0.0)


@dataclass(frozen=True)
class PlanResult:
    """The outcome of one plan.

    Attributes:
        status: how it ended.
        reason: one human-readable line (why it was refused, what ran out, what was found).
        start: the start vertex id (None when refused before it was resolved).
        goal: the goal vertex id (None when refused before it was resolved).
        vertices: (L + 1,) int64 vertex ids of the path, start first (empty unless FOUND).
        edges: (L,) int64 edge ids of the path in traversal order (empty unless FOUND).
        checks: every check in order (edge, outcome, stage, selection and check time).
        cost: the path's length in the domain's unit (0 unless FOUND).
        stage: which stage proved the path (None unless FOUND).
        query: ``tree:<name>`` for a precomputed tree, ``online`` for a library built for this query.
        query_cached: the query's library and tree came from the planner's query cache (built or loaded
            by an earlier plan of the same query) rather than being built for this plan.
        library_size: m of the query's library (0 when it had none).
        timings: where the time went.
        new_states: for an off-graph start or goal, its new vertex id -> (D,) state (ids from V on).
        motions: the new edges joining them, edge id -> (K, D) states along it, tail first (ids from E on).
        improvements: with an ``improve_budget``, every verified path in the order found, strictly shorter
            each time; the last one is this result's path. Empty without one.
        improve_stop: why the improvement stopped (``optimal``, ``checks``, ``seconds``, ``patience``,
            ``plan_checks``, ``plan_time``); empty without an ``improve_budget``.
        growth: what roadmap growth did when the plan grew the graph (None when it did not); then
            ``vertices``, ``edges``, ``checks`` and ``motions`` use the ids of ``growth.query``.
        cause: why it failed, as a value, where the planner can tell: the end outside or walled in, or for
            BUDGET_EXHAUSTED the budget that ran out (``CHECK_BUDGET``, ``TIME_BUDGET``); None otherwise, and
            when FOUND.
    """

    status: PlanStatus
    reason: str
    start: int | None = None
    goal: int | None = None
    vertices: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    edges: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    checks: tuple[CheckRecord, ...] = ()
    cost: float = 0.0
    stage: PlanStage | None = None
    query: str = ""
    query_cached: bool = False
    library_size: int = 0
    timings: PlanTimings = field(default_factory=PlanTimings)
    new_states: Mapping[int, FloatArray] = field(default_factory=dict)
    motions: Mapping[int, FloatArray] = field(default_factory=dict)
    improvements: tuple[Improvement, ...] = ()
    improve_stop: str = ""
    growth: GrowthReport | None = None
    cause: PlanCause | None = None

    @property
    def found(self) -> bool:
        """True when a verified path was found."""
        return self.status is PlanStatus.FOUND

    @property
    def num_checks(self) -> int:
        """How many edges were checked."""
        return len(self.checks)

    def outcomes(self) -> dict[int, bool]:
        """Every checked edge and its outcome."""
        return {c.edge: c.free for c in self.checks}

    def raise_for_status(self) -> PlanResult:
        """Return ``self`` when FOUND, else raise :class:`PlanningError` with the reason."""
        if not self.found:
            raise PlanningError(f"{self.status.value}: {self.reason}")
        return self


def library_stage(checks: list[CheckRecord]) -> PlanStage:
    """The stage that proved a library path: the stage of the last check (tree, BiSECt or library)."""
    last = checks[-1].stage if checks else ""
    if last == "tree":
        return PlanStage.TREE
    if last == "bisect":
        return PlanStage.BISECT
    return PlanStage.LIBRARY


def plan_timings(checks: list[CheckRecord] | tuple[CheckRecord, ...], library_s: float, t_begin: float) -> PlanTimings:
    """The timings of a plan from its checks, the library time and its start (``time.perf_counter``)."""
    return PlanTimings(
        library_s=library_s,
        selection_s=sum(c.select_ms for c in checks) / 1e3,
        checks_s=sum(c.check_ms for c in checks) / 1e3,
        total_s=time.perf_counter() - t_begin,
    )


def unproven_result(
    model: QueryModel,
    status: PlanStatus,
    reason: str,
    checks: list[CheckRecord],
    t_model: float,
    t_begin: float,
    growth: GrowthReport | None = None,
) -> PlanResult:
    """A result without a path (no path in the graph, or a budget ran out), with its check log."""
    return PlanResult(
        status,
        reason,
        model.start,
        model.goal,
        checks=tuple(checks),
        query=model.label,
        query_cached=model.reused,
        library_size=0 if model.library is None else model.library.num_paths,
        timings=plan_timings(checks, t_model, t_begin),
        growth=growth,
    )


def exhausted_result(
    model: QueryModel,
    ran_out: PlanCause,
    checks: list[CheckRecord],
    t_model: float,
    t_begin: float,
    growth: GrowthReport | None = None,
) -> PlanResult:
    """The BUDGET_EXHAUSTED result of a plan whose ``ran_out`` budget (``CHECK_BUDGET``, ``TIME_BUDGET``) ran out."""
    what = "check budget" if ran_out is PlanCause.CHECK_BUDGET else "time budget"
    reason = f"the {what} ran out after {len(checks)} checks before a path was verified"
    if growth is not None:
        reason += f"; {growth.summary()}"
    result = unproven_result(model, PlanStatus.BUDGET_EXHAUSTED, reason, checks, t_model, t_begin, growth)
    return dataclasses.replace(result, cause=ran_out)


def found_result(
    model: QueryModel,
    path_edges: IntArray,
    checks: list[CheckRecord],
    stage: PlanStage,
    times: tuple[float, float],
    growth: GrowthReport | None = None,
) -> PlanResult:
    """The FOUND result of a verified path of the query's graph (of ``growth.query`` when it grew).

    ``times`` is ``(seconds building the query's model, time.perf_counter() at the plan's start)``.
    """
    query = model.query if growth is None else growth.query
    edges = np.asarray(path_edges, dtype=np.int64)
    cost = float(query.graph.lengths[edges].sum())
    vertices = vertex_sequence(query.graph.edges, query.start, edges)
    states = query.graph.vertex_states
    new_states = dict(query.new_states)
    if growth is not None and states is not None:  # the grown vertices on the path
        first_grown = growth.query.graph.num_vertices - growth.vertices_added
        new_states.update({int(v): states[int(v)] for v in vertices.tolist() if v >= first_grown})
    grown = f"; {growth.summary()}" if growth is not None else ""
    return PlanResult(
        PlanStatus.FOUND,
        f"path of {edges.size} edges (cost {cost:.4g}) verified free after {len(checks)} checks{grown}",
        query.start,
        query.goal,
        vertices=vertices,
        edges=edges,
        checks=tuple(checks),
        cost=cost,
        stage=stage,
        query=model.label,
        query_cached=model.reused,
        library_size=0 if model.library is None else model.library.num_paths,
        timings=plan_timings(checks, times[0], times[1]),
        new_states=new_states,
        motions={e: query.motions[e] for e in edges.tolist() if e in query.motions},
        growth=growth,
    )


def trivial_result(vertex: int, t_begin: float) -> PlanResult:
    """The FOUND result of a query whose start and goal are the same vertex: the empty path."""
    return PlanResult(
        PlanStatus.FOUND,
        "start and goal are the same vertex: the empty path",
        vertex,
        vertex,
        vertices=np.array([vertex], dtype=np.int64),
        stage=PlanStage.TRIVIAL,
        timings=plan_timings((), 0.0, t_begin),
    )
