"""The edge-oracle seam and the one episode runner every policy goes through.

A policy only proposes edges (``select``) and hears outcomes (``observe``); the runner owns the
check log and decides when a library path is proven free. It returns a path only when every one
of its edges was checked free in this episode: that is the planner's safety invariant.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import IntArray
from drd_planner.core.library import PathLibrary
from drd_planner.core.status import PlanCause, PlanStatus
from drd_planner.exceptions import PolicyError, UnverifiedPathError


@runtime_checkable
class EdgeOracle(Protocol):
    """Answers whether an edge is collision-free: a row of X in benchmarks, FCL in the node."""

    def check(self, edge: int) -> bool:
        """True when ``edge`` is collision-free."""
        ...


class Policy(Protocol):
    """An edge-selection policy driven by :func:`run_episode`."""

    @property
    def name(self) -> str:
        """Registry name of the policy."""
        ...

    @property
    def stage(self) -> str:
        """Which part of the policy chose the last edge (``tree``, ``bisect``, ...)."""
        ...

    def select(self) -> int | None:
        """The next edge to check, or None when the policy has nothing left to ask."""
        ...

    def observe(self, edge: int, free: bool) -> None:
        """Hear the outcome of checking ``edge``."""
        ...


@runtime_checkable
class GraphPathPolicy(Policy, Protocol):
    """A policy whose answer is its own path in the graph, not a library path (LazySP).

    The runner ends its episode with FOUND (``path_index`` None, ``path_edges`` the proposed
    path) once every edge of :meth:`proposed_path` was checked free, and with NO_PATH when that
    returns None. Library paths stop it too only if :attr:`stops_on_library_path` is True.
    """

    @property
    def stops_on_library_path(self) -> bool:
        """Whether a proven-free library path (or every library path blocked) also ends the episode."""
        ...

    @property
    def max_checks(self) -> int | None:
        """The policy's own check budget (the runner uses the smaller of it and the caller's)."""
        ...

    def proposed_path(self) -> IntArray | None:
        """Edge ids, start to goal, of the path the policy stands behind now; None if none exists."""
        ...


class TableOracle:
    """An oracle that answers from one world's row of the outcome matrix X."""

    def __init__(self, outcomes: npt.ArrayLike) -> None:
        """``outcomes``: (E,) bool, True where the edge is free."""
        self._outcomes = np.asarray(outcomes, dtype=bool).ravel()
        self._calls = 0

    @property
    def calls(self) -> int:
        """How many checks were asked of this oracle."""
        return self._calls

    def check(self, edge: int) -> bool:
        """Look the edge up."""
        self._calls += 1
        return bool(self._outcomes[edge])


#: How an episode ended: its status, and why it found no path (a :class:`PlanCause`, or None).
Ending = tuple[PlanStatus, PlanCause | None]

_FOUND: Ending = (PlanStatus.FOUND, None)
_NO_PATH: Ending = (PlanStatus.NO_PATH, None)
_GAVE_UP: Ending = (PlanStatus.BUDGET_EXHAUSTED, PlanCause.POLICY_GAVE_UP)
_CHECK_BUDGET: Ending = (PlanStatus.BUDGET_EXHAUSTED, PlanCause.CHECK_BUDGET)
_TIME_BUDGET: Ending = (PlanStatus.BUDGET_EXHAUSTED, PlanCause.TIME_BUDGET)


@dataclass(frozen=True)
class CheckRecord:
    """One collision check: which edge, its outcome, who chose it and how long each part took."""

    step: int
    edge: int
    free: bool
    stage: str
    select_ms: float
    check_ms: float


@dataclass(frozen=True)
class EpisodeResult:
    """The ordered check log and the outcome of one episode.

    Attributes:
        checks: every check in order.
        status: how the episode ended: FOUND, NO_PATH or BUDGET_EXHAUSTED (see :func:`run_episode`).
        path_index: index of the proven-free library path, when status is FOUND (None when a
            :class:`GraphPathPolicy` found its own path).
        path_edges: the proven-free path's edge ids in traversal order.
        blocked_evidence: for NO_PATH, (m,) the checked blocked edge that rules out each path.
        cause: for BUDGET_EXHAUSTED, what stopped it: ``CHECK_BUDGET``, ``TIME_BUDGET`` or
            ``POLICY_GAVE_UP``; None otherwise.
    """

    checks: tuple[CheckRecord, ...]
    status: PlanStatus
    path_index: int | None
    path_edges: IntArray | None
    blocked_evidence: IntArray | None = None
    cause: PlanCause | None = None

    @property
    def num_checks(self) -> int:
        """Number of distinct edges checked."""
        return len(self.checks)

    @property
    def success(self) -> bool:
        """True when a path was proven free."""
        return self.status is PlanStatus.FOUND

    @property
    def ran_out(self) -> PlanCause | None:
        """The budget that ran out (``CHECK_BUDGET`` or ``TIME_BUDGET``); None otherwise (a policy giving up too)."""
        return self.cause if self.cause is not None and self.cause.is_budget else None

    def total_cost(self, edge_costs: npt.ArrayLike) -> float:
        """Sum of the checked edges' costs."""
        costs = np.asarray(edge_costs, dtype=np.float64)
        return float(sum(costs[c.edge] for c in self.checks))

    def mean_select_ms(self) -> float:
        """Mean selection time per check in milliseconds (0 when nothing was checked)."""
        return float(np.mean([c.select_ms for c in self.checks])) if self.checks else 0.0


class _LibraryProgress:
    """Per-path bookkeeping of unchecked and blocked edges (independent of any policy).

    Attributes:
        remaining: (m,) int64 edges of each path not yet checked free (a blocked edge stays counted, so a
            path reaches 0 only when every edge of it was checked free).
        blocker: (m,) int64 the first checked blocked edge of each path, -1 while it has none.
    """

    def __init__(self, library: PathLibrary) -> None:
        self._library = library
        self.remaining = np.array([p.size for p in library.path_edges], dtype=np.int64)
        self.blocker = np.full(library.num_paths, -1, dtype=np.int64)
        self._proven: list[int] = np.flatnonzero(self.remaining == 0).tolist()  # paths proven free, as found
        self._unblocked = library.num_paths  # paths with no checked blocked edge

    def record(self, edge: int, free: bool) -> None:
        paths = self._library.paths_through(edge)
        if free:
            remaining = self.remaining[paths] - 1
            self.remaining[paths] = remaining
            if not remaining.all():
                self._proven.extend(paths[remaining == 0].tolist())
        else:
            fresh = paths[self.blocker[paths] < 0]
            self.blocker[fresh] = edge
            self._unblocked -= int(fresh.size)

    def proven_path(self, edge_costs: npt.NDArray[np.float64]) -> int | None:
        """Cheapest (then lowest-index) path whose every edge is checked free."""
        if not self._proven:
            return None
        done = np.array(sorted(self._proven), dtype=np.int64)
        costs = np.array([edge_costs[self._library.path_edges[i]].sum() for i in done])
        return int(done[int(np.argmin(costs))])

    def all_blocked(self) -> bool:
        return self._unblocked == 0


def append_episode(checks: list[CheckRecord], known: dict[int, bool], episode: EpisodeResult) -> None:
    """Append an episode's checks to a plan's log (steps numbered on after it) and their outcomes to ``known``.

    A plan runs its stages as episodes, each numbering its checks from 0; the plan's log numbers them on.
    """
    offset = len(checks)
    checks.extend(dataclasses.replace(c, step=c.step + offset) for c in episode.checks)
    known.update({c.edge: c.free for c in episode.checks})


def run_episode(
    library: PathLibrary | None,
    edge_costs: npt.ArrayLike,
    policy: Policy,
    oracle: EdgeOracle,
    *,
    max_checks: int | None = None,
    deadline: float | None = None,
    known: Mapping[int, bool] | None = None,
) -> EpisodeResult:
    """Drive ``policy`` against ``oracle`` until a library path is proven free or none can be.

    The episode ends when (1) some library path has every edge checked free (FOUND), (2) every
    library path has a checked blocked edge (NO_PATH), or BUDGET_EXHAUSTED with its cause when (3) the
    policy has nothing left to ask (``POLICY_GAVE_UP``: nothing proven either way), (4) ``max_checks``
    checks were made (``CHECK_BUDGET``), or (5) ``time.perf_counter()`` passed ``deadline`` before a
    selection (``TIME_BUDGET``).

    A :class:`GraphPathPolicy` is instead stopped by its own path: before each selection, FOUND
    (``path_index`` None) when every edge of ``proposed_path()`` was checked free, NO_PATH (no
    ``blocked_evidence``) when it is None. Rules (1) and (2) then apply only if the policy's
    ``stops_on_library_path`` says so, and its ``max_checks`` caps the episode too.

    ``library`` may be None only for a :class:`GraphPathPolicy` that does not stop on library paths.

    ``known`` holds outcomes checked earlier in the same plan (by an earlier stage, on the same maps):
    they count as checked for the proof of a path and may not be chosen again; the policy must
    already know them. They are not in this episode's log and do not count against ``max_checks``.

    Raises:
        PolicyError: the policy chose an edge outside the graph or one already checked.
        UnverifiedPathError: never, unless the bookkeeping itself is broken (a last safety net).
    """
    episode = _Episode(library, edge_costs, policy, oracle, max_checks, known)
    ending = episode.settled_by_known()
    if ending is None:
        ending = episode.run(deadline)
    return episode.result(ending)


class _Episode:
    """The state of one :func:`run_episode`: the outcomes so far, the check log and the library progress."""

    def __init__(
        self,
        library: PathLibrary | None,
        edge_costs: npt.ArrayLike,
        policy: Policy,
        oracle: EdgeOracle,
        max_checks: int | None,
        known: Mapping[int, bool] | None,
    ) -> None:
        """See :func:`run_episode`; records the ``known`` outcomes (PolicyError: no library to stop on)."""
        self.costs = np.asarray(edge_costs, dtype=np.float64)
        self.policy = policy
        self.oracle = oracle
        self.graph_policy = policy if isinstance(policy, GraphPathPolicy) else None
        self.library_stops = self.graph_policy is None or self.graph_policy.stops_on_library_path
        if library is None and self.library_stops:
            raise PolicyError(f"policy {policy.name} stops on library paths, so its episode needs a library")
        self.library = library
        self.num_edges = self.costs.size if library is None else library.num_edges
        self.progress = _LibraryProgress(library) if library is not None else None
        self.limit = max_checks
        if self.graph_policy is not None and self.graph_policy.max_checks is not None:
            cap = self.graph_policy.max_checks
            self.limit = cap if self.limit is None else min(self.limit, cap)
        self.outcome: dict[int, bool] = {}
        for edge, free in (known or {}).items():
            self.outcome[int(edge)] = bool(free)
            if self.progress is not None:
                self.progress.record(int(edge), bool(free))
        self.log: list[CheckRecord] = []
        self.own_path: IntArray | None = None

    def settled_by_known(self) -> Ending | None:
        """FOUND or NO_PATH when the earlier checks already settle the library, else None."""
        if self.progress is None or not self.library_stops or not self.outcome:
            return None
        if self.progress.proven_path(self.costs) is not None:
            return _FOUND
        if self.progress.all_blocked():
            return _NO_PATH
        return None

    def run(self, deadline: float | None) -> Ending:
        """Select, check and observe until one of the stopping rules of :func:`run_episode` applies."""
        while True:
            t0 = time.perf_counter()  # a graph policy's re-planning in proposed_path() is selection time
            ending = self._stop_before_selection(t0, deadline)
            if ending is not None:
                return ending
            choice = self.policy.select()
            t1 = time.perf_counter()
            if choice is None:
                return _GAVE_UP
            ending = self._check(int(choice), t0, t1)
            if ending is not None:
                return ending

    def _stop_before_selection(self, t0: float, deadline: float | None) -> Ending | None:
        """The graph policy's own path rules, then the check cap, then the deadline."""
        if self.graph_policy is not None:
            proposed = self.graph_policy.proposed_path()
            if proposed is None:
                return _NO_PATH
            if all(self.outcome.get(int(e)) is True for e in proposed):
                self.own_path = np.array(proposed, dtype=np.int64)
                return _FOUND
        if self.limit is not None and len(self.log) >= self.limit:
            return _CHECK_BUDGET
        if deadline is not None and t0 >= deadline:
            return _TIME_BUDGET
        return None

    def _check(self, edge: int, t0: float, t1: float) -> Ending | None:
        """Check ``edge`` (chosen between ``t0`` and ``t1``), log it, tell the policy; the ending if it ends."""
        if not 0 <= edge < self.num_edges:
            raise PolicyError(f"policy {self.policy.name} chose edge {edge}, outside [0, {self.num_edges})")
        if edge in self.outcome:
            raise PolicyError(f"policy {self.policy.name} chose edge {edge} a second time")
        free = bool(self.oracle.check(edge))
        t2 = time.perf_counter()
        self.outcome[edge] = free
        self.log.append(CheckRecord(len(self.log), edge, free, self.policy.stage, (t1 - t0) * 1e3, (t2 - t1) * 1e3))
        self.policy.observe(edge, free)
        progress = self.progress
        if progress is None:
            return None
        progress.record(edge, free)
        if not self.library_stops:
            return None
        if free and progress.proven_path(self.costs) is not None:
            return _FOUND
        if not free and progress.all_blocked():
            return _NO_PATH
        return None

    def result(self, ending: Ending) -> EpisodeResult:
        """The episode's result; the returned path is verified against the outcomes (the safety net)."""
        status, cause = ending
        path_index: int | None = None
        path_edges: IntArray | None = None
        progress = self.progress
        if self.own_path is not None:
            path_edges = self.own_path
        elif status is PlanStatus.FOUND and progress is not None and self.library is not None:
            path_index = progress.proven_path(self.costs)
            if path_index is not None:
                path_edges = self.library.path_edges[path_index]
        if path_edges is not None:
            verify_path(path_edges, self.outcome)
        evidence = None
        if status is PlanStatus.NO_PATH and progress is not None and self.library_stops:
            if progress.all_blocked():
                evidence = progress.blocker.copy()
        return EpisodeResult(tuple(self.log), status, path_index, path_edges, evidence, cause)


def verify_path(path_edges: Sequence[int] | IntArray, outcome: dict[int, bool]) -> None:
    """Raise :class:`UnverifiedPathError` unless every edge was checked and found free."""
    for e in np.asarray(path_edges, dtype=np.int64).tolist():
        if outcome.get(int(e)) is not True:
            raise UnverifiedPathError(f"edge {e} of the returned path was not checked free")
