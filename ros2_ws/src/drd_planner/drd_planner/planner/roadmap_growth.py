"""Roadmap growth on demand: when the graph has no free path, add vertices and edges where it is cut, lazily.

The planner's graph stage (:mod:`drd_planner.planner.graph_fallback`) says "no path" exactly when the edges
checked blocked disconnect start and goal in the query's graph. A roadmap is a finite sample of the free
space, so that often means "no path *in this roadmap*" while the world has one. With a domain that can
sample its valid states (a connector with a :class:`~drd_planner.planner.state_sampler.StateSampler`, the arm
today) the planner then grows the graph, round after round:

1. new vertices where the blocked region cuts the graph and between the start's and the goal's sides
   (:mod:`~drd_planner.planner.growth_samples`: Gaussian samples around the frontiers of their
   known-reachable components, bridge samples, a few uniform ones), each statically valid, joined to its k
   nearest vertices by straight motions at the check resolution (statically valid too);
2. each new edge gets a prior free probability like every motion off the graph: its outcome in each training
   world is imputed from the graph edges it overlaps (:func:`~drd_planner.planner.connect.imputed_outcomes`);
3. the lazy graph search (:func:`lazy_search`, the graph stage's LazySP with the posterior edge weights) runs
   again on the grown graph, reusing every outcome known in the plan; new edges are checked only when a
   candidate path needs them, through the oracle's ``check_motion``.

It stops at the first verified path, or when a budget ends (:class:`GrowthSettings`: rounds, new vertices,
seconds, checks; and the plan's own ``max_checks`` and ``time_budget_s``). Random draws come from the plan's
seed only: the same seed gives the same checks and the same path (unless a time budget cuts a run short).
"""

from __future__ import annotations

import math
import time
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.episode import CheckRecord, EdgeOracle, EpisodeResult, append_episode, run_episode
from drd_planner.core.lazysp import LazySP, LazySPSettings
from drd_planner.core.status import PlanCause, PlanStatus
from drd_planner.exceptions import ProblemError
from drd_planner.planner.connect import EdgeSampleIndex, MotionOracle
from drd_planner.planner.graph_fallback import (
    DEFAULT_FALLBACK_KAPPA,
    FALLBACK_SELECTOR,
    fallback_edge_weights,
    posterior_free_probability,
)
from drd_planner.planner.grown_graph import GrownGraph, new_pairs
from drd_planner.planner.growth_samples import (
    SampleMix,
    SegmentMaker,
    bridge_pairs,
    draw_states,
    frontier,
    known_reachable,
    nearest_pairs,
    parent_pairs,
    straight_motions,
)
from drd_planner.planner.prior import WorldPrior
from drd_planner.planner.query_graph import MotionDispatch, QueryGraph
from drd_planner.planner.result import GrowthReport
from drd_planner.planner.state_sampler import StateSampler

__all__ = [
    "DEFAULT_GROWTH",
    "GROWTH_STAGE",
    "GrowthLimits",
    "GrowthOutcome",
    "GrowthSettings",
    "RoadmapGrowth",
    "lazy_search",
]

#: Stage label of the checks made while the graph grows.
GROWTH_STAGE = "grow"
#: Second word of the growth's random stream, so that it differs from the policies' (same plan seed).
_GROWTH_STREAM = 0x6B0


@dataclass(frozen=True)
class GrowthSettings:
    """How far and how the planner grows a graph that has no free path (see the module docstring).

    Attributes:
        max_rounds: growth rounds at most (count).
        max_vertices: new vertices at most in one plan (count).
        seconds: wall-clock seconds of growth at most (s); None: only the plan's ``time_budget_s``.
        max_checks: checks after growth began at most (count); None: only the plan's ``max_checks``.
        samples_per_round: candidate states drawn per round (count), before the static test.
        neighbours: vertices each new vertex is joined to, at most (count).
        start_share: fraction of a round's samples drawn around the start side's frontier.
        goal_share: fraction drawn around the goal side's frontier.
        bridge_share: fraction drawn between the two frontiers; the rest is uniform.
        sigma_range: (low, high) standard deviation of the Gaussian samples, as fractions of the graph's
            median edge length (drawn log-uniformly).
        reach_fraction: new edges are at most this fraction of the connector's reach long (the graph's
            longest edge).
        bridges: direct edges added per round between the nearest vertices of the start's and the goal's
            known-reachable parts (count; 0: none).
        max_joins: motions joining an off-graph start or goal at most, when the connector can offer more
            than its first ones (:mod:`~drd_planner.planner.join_growth`; count; None: every vertex a flyable
            motion reaches and that can still lead to the other end, within the time and check budgets).
        join_batch: joins offered per off-graph endpoint in a join-growth round (count): as many as it
            already has, at least this many, in the order of their weight under the prior (a vectorised sketch
            of each motion, :class:`~drd_planner.planner.join_ranking.PriorRanking`); None: every join left at
            once (a flyable motion to each lattice vertex is built and imputed: seconds on ``heli_lines``).
        graph_checks_first: checks the graph stage makes before a growth that may begin early (more joins of
            an off-graph start or goal, :attr:`GraphGrowth.starts_early`) begins, when the graph stage has
            not verified a path by then (count; None: the graph stage first proves that the graph has no free
            path, which can take hundreds of checks when every path through the first joins is blocked).
    """

    max_rounds: int = 40
    max_vertices: int = 3000
    seconds: float | None = 10.0
    max_checks: int | None = None
    samples_per_round: int = 60
    neighbours: int = 8
    start_share: float = 0.3
    goal_share: float = 0.3
    bridge_share: float = 0.2
    sigma_range: tuple[float, float] = (0.1, 0.6)
    reach_fraction: float = 1.0
    bridges: int = 8
    max_joins: int | None = None
    join_batch: int | None = 64
    graph_checks_first: int | None = 64

    def __post_init__(self) -> None:
        counts = (self.max_rounds, self.max_vertices, self.samples_per_round, self.neighbours)
        shares = (self.start_share, self.goal_share, self.bridge_share)
        low, high = self.sigma_range
        if (
            min(counts) < 1
            or self.bridges < 0
            or (self.max_joins is not None and self.max_joins < 1)
            or (self.join_batch is not None and self.join_batch < 1)
            or (self.graph_checks_first is not None and self.graph_checks_first < 1)
            or (self.max_checks is not None and self.max_checks < 1)
        ):
            raise ProblemError(
                f"growth counts must be at least 1, got {counts}, max_checks {self.max_checks}, max_joins "
                f"{self.max_joins}, join_batch {self.join_batch} and graph_checks_first {self.graph_checks_first}"
            )
        if self.seconds is not None and not (math.isfinite(self.seconds) and self.seconds > 0):
            raise ProblemError(f"growth seconds must be positive, got {self.seconds}")
        if min(shares) < 0 or sum(shares) > 1 + 1e-9:
            raise ProblemError(f"growth shares must be >= 0 and sum to at most 1, got {shares}")
        if not (0 < low <= high and math.isfinite(high)) or not 0 < self.reach_fraction <= 1:
            raise ProblemError(
                f"growth needs 0 < sigma low <= high and 0 < reach_fraction <= 1, got {self.sigma_range} "
                f"and {self.reach_fraction}"
            )


#: The planner's default growth (:class:`GrowthSettings` defaults).
DEFAULT_GROWTH = GrowthSettings()


@dataclass(frozen=True)
class GrowthOutcome:
    """How growth ended.

    Attributes:
        status: FOUND, NO_PATH (a growth budget ended first, or nothing more to add) or BUDGET_EXHAUSTED
            (one of the plan's budgets ran out).
        path_edges: (L,) edge ids of the verified path in the grown graph (None unless FOUND).
        report: what growth did, with the grown query.
        cause: for BUDGET_EXHAUSTED, the plan's budget that ran out (``CHECK_BUDGET``, ``TIME_BUDGET``).
    """

    status: PlanStatus
    path_edges: IntArray | None
    report: GrowthReport
    cause: PlanCause | None = None


def lazy_search(
    prior: WorldPrior,
    query: QueryGraph,
    oracle: EdgeOracle,
    known: Mapping[int, bool],
    *,
    budget: int | None,
    deadline: float | None,
    stage: str,
) -> EpisodeResult:
    """LazySP over the query's whole graph with the prior's posterior edge weights, reusing ``known``.

    The graph stage of :class:`~drd_planner.planner.Planner` and every growth round (see
    :mod:`~drd_planner.planner.graph_fallback` for the weights and the selector).
    """
    theta = posterior_free_probability(
        query.worlds,
        prior.world_weights,
        known,
        num_edges=query.graph.num_edges,
        alpha=prior.alpha,
        pseudo_count=prior.pseudo_count or DEFAULT_FALLBACK_KAPPA,
    )
    search = LazySP(
        query.graph,
        query.start,
        query.goal,
        LazySPSettings(selector=FALLBACK_SELECTOR, max_checks=None),
        edge_weights=fallback_edge_weights(query.graph, theta),
        observations=known,
        stage=stage,
        name="graph_fallback",
    )
    return run_episode(None, query.edge_costs, search, oracle, max_checks=budget, deadline=deadline, known=known)


@dataclass(frozen=True)
class GrowthLimits:
    """The plan's check budget and the earliest deadline (the plan's or the growth's own)."""

    max_checks: int | None
    deadline: float | None


class GraphGrowth(ABC):
    """The growth loop of one query's graph: grow, search lazily, until a path is verified or a budget ends.

    Each round a subclass adds to the graph (:meth:`_grow`: new vertices and edges of a roadmap, or more
    motions joining an off-graph start or goal); then the lazy graph search runs on the grown graph, reusing
    every outcome known. The start's and the goal's own states are checked first.

    Args:
        prior: the prior (training worlds for the new edges' imputed outcomes, alpha and kappa).
        query: the query's graph after the graph stage found no path.
        index: points along the prior's graph edges (for the imputation).
        settings: the growth's budget (and a subclass's shape).
    """

    #: Whether growth may begin before the graph stage has proved that the query's graph has no free path
    #: (after :attr:`GrowthSettings.graph_checks_first` checks); the planner then finishes that proof after
    #: a growth that found no path. A growth whose new parts are placed by where the blocked region is known
    #: to cut the graph (a roadmap's) waits for the proof.
    starts_early: ClassVar[bool] = False

    def __init__(
        self,
        prior: WorldPrior,
        query: QueryGraph,
        index: EdgeSampleIndex,
        settings: GrowthSettings = DEFAULT_GROWTH,
    ) -> None:
        self.prior, self.settings = prior, settings
        self.grown = GrownGraph(query, index, prior.worlds)
        self.rounds = 0
        self.checks_at_start = 0
        self.state_checks = 0

    @abstractmethod
    def _grow(
        self,
        rng: np.random.Generator,
        oracle: MotionOracle,
        known: dict[int, bool],
        checks: list[CheckRecord],
        limits: GrowthLimits,
    ) -> bool:
        """Add to :attr:`grown` (one round); False when nothing more can be added (growth then stops)."""

    def run(
        self,
        oracle: MotionOracle,
        known: dict[int, bool],
        checks: list[CheckRecord],
        *,
        seed: int,
        max_checks: int | None,
        deadline: float | None,
    ) -> GrowthOutcome:
        """Grow and search until a path is verified or a budget ends; ``known`` and ``checks`` are extended.

        Args:
            oracle: the plan's oracle (graph edges by ``check``, motions by ``check_motion``).
            known: every outcome of the plan so far (edge id -> free).
            checks: the plan's check log (steps from 0).
            seed: the plan's seed.
            max_checks: the plan's check budget (None: none).
            deadline: the plan's deadline (``time.perf_counter()``; None: none).
        """
        settings = self.settings
        rng = np.random.default_rng([int(seed) % (1 << 64), _GROWTH_STREAM])
        self.checks_at_start = len(checks)
        own_deadline = None if settings.seconds is None else time.perf_counter() + settings.seconds
        ends = [d for d in (deadline, own_deadline) if d is not None]
        limits = GrowthLimits(max_checks, min(ends) if ends else None)
        stop = self._budget_stop(checks, max_checks, deadline, own_deadline)
        stop = stop or self._check_ends(oracle, known, checks)
        while not stop:
            stop = self._budget_stop(checks, max_checks, deadline, own_deadline)
            if stop:
                break
            self.rounds += 1
            if not self._grow(rng, oracle, known, checks, limits):
                stop = "exhausted"
                break
            query = self.grown.query()
            episode = lazy_search(
                self.prior,
                query,
                MotionDispatch(oracle, query.motions),
                known,
                budget=self._checks_left(checks, max_checks),
                deadline=limits.deadline,
                stage=GROWTH_STAGE,
            )
            append_episode(checks, known, episode)
            if episode.success and episode.path_edges is not None:
                return GrowthOutcome(PlanStatus.FOUND, episode.path_edges, self._report("path", checks))
            if episode.ran_out is not None:
                stop = self._budget_stop(checks, max_checks, deadline, own_deadline) or "checks"
        ran_out = {"plan_checks": PlanCause.CHECK_BUDGET, "plan_time": PlanCause.TIME_BUDGET}.get(stop)
        status = PlanStatus.NO_PATH if ran_out is None else PlanStatus.BUDGET_EXHAUSTED
        return GrowthOutcome(status, None, self._report(stop, checks), ran_out)

    def _checks_left(self, checks: list[CheckRecord], max_checks: int | None) -> int | None:
        """Checks this round may make: the least of the plan's and the growth's budgets left (None: no limit)."""
        limits = []
        if max_checks is not None:
            limits.append(max_checks - len(checks))
        if self.settings.max_checks is not None:
            limits.append(self.settings.max_checks - (len(checks) - self.checks_at_start))
        return min(limits) if limits else None

    def _budget_stop(
        self, checks: list[CheckRecord], max_checks: int | None, deadline: float | None, own: float | None
    ) -> str:
        """The name of the budget that has ended, or "" (the plan's budgets first)."""
        now, used, settings = time.perf_counter(), len(checks) - self.checks_at_start, self.settings
        ended = (
            ("plan_checks", max_checks is not None and len(checks) >= max_checks),
            ("plan_time", deadline is not None and now >= deadline),
            ("checks", settings.max_checks is not None and used >= settings.max_checks),
            ("seconds", own is not None and now >= own),
            ("rounds", self.rounds >= settings.max_rounds),
            ("vertices", self.grown.vertices_added >= settings.max_vertices),
        )
        return next((name for name, over in ended if over), "")

    def _check_ends(self, oracle: MotionOracle, known: dict[int, bool], checks: list[CheckRecord]) -> str:
        """Check the start's and the goal's own states first (their vertex edges, logged).

        Returns ``start_blocked`` or ``goal_blocked`` when one is blocked (no path can exist), else "".
        """
        base = self.grown.base
        for vertex, label in ((base.start, "start"), (base.goal, "goal")):
            edge = self.grown.add_vertex_edge(vertex)
            if not self._logged_check(edge, oracle, known, checks):
                return f"{label}_blocked"
        return ""

    def _logged_check(self, edge: int, oracle: MotionOracle, known: dict[int, bool], checks: list[CheckRecord]) -> bool:
        """Check the vertex edge ``edge`` (its one state) through the oracle, logged as a growth check."""
        t0 = time.perf_counter()
        free = bool(oracle.check_motion(self.grown.motions[edge]))
        checks.append(CheckRecord(len(checks), edge, free, GROWTH_STAGE, 0.0, (time.perf_counter() - t0) * 1e3))
        known[edge] = free
        self.state_checks += 1
        return free

    def _report(self, stop: str, checks: list[CheckRecord]) -> GrowthReport:
        return GrowthReport(
            rounds=self.rounds,
            vertices_added=self.grown.vertices_added,
            edges_added=self.grown.edges_added,
            checks=len(checks) - self.checks_at_start,
            stop=stop,
            query=self.grown.query(),
            state_checks=self.state_checks,
        )


class RoadmapGrowth(GraphGrowth):
    """Grows a roadmap with new valid states where it is cut (see the module docstring).

    Args:
        prior: the prior (training worlds for the new edges' imputed outcomes, alpha and kappa).
        query: the query's graph after the graph stage found no path.
        connector: makes the straight motions of new edges (``segment``).
        sampler: the domain's valid states.
        index: points along the prior's graph edges (for the imputation).
        settings: the growth's shape and budget.
    """

    def __init__(
        self,
        prior: WorldPrior,
        query: QueryGraph,
        connector: SegmentMaker,
        sampler: StateSampler,
        index: EdgeSampleIndex,
        settings: GrowthSettings = DEFAULT_GROWTH,
    ) -> None:
        super().__init__(prior, query, index, settings)
        self.connector, self.sampler = connector, sampler
        scale = float(np.median(prior.graph.lengths)) if prior.graph.num_edges else 1.0
        low, high = settings.sigma_range
        self.mix = SampleMix(
            settings.samples_per_round,
            settings.start_share,
            settings.goal_share,
            settings.bridge_share,
            (low * scale, high * scale),
        )
        self.reach = settings.reach_fraction * float(prior.graph.lengths.max(initial=scale))

    def _grow(
        self,
        rng: np.random.Generator,
        oracle: MotionOracle,
        known: dict[int, bool],
        checks: list[CheckRecord],
        limits: GrowthLimits,
    ) -> bool:
        """One round of new vertices and edges (see :mod:`~drd_planner.planner.growth_samples`).

        New valid states around the frontiers and between them, each checked (its vertex edge), the free
        ones joined to their parents and nearest vertices; and direct edges between the nearest vertices of
        the start's and the goal's known-reachable parts.
        """
        grown, base = self.grown, self.grown.base
        outcome = np.zeros(grown.edges.shape[0], dtype=np.int8)
        for edge, free in known.items():
            outcome[edge] = 1 if free else -1
        count = grown.num_vertices
        parts = [known_reachable(count, grown.edges, outcome > 0, v) for v in (base.start, base.goal)]
        start_side, goal_side = (frontier(part, grown.edges, outcome < 0, count) for part in parts)
        states, parents = draw_states(rng, self.sampler, grown.states, (start_side, goal_side), self.mix)
        left = self.settings.max_vertices - grown.vertices_added
        budget = self._checks_left(checks, limits.max_checks)
        if budget is not None:
            left = min(left, max(budget, 0))
        states, parents = states[:left], parents[:left]
        checked = self._check_states(states, oracle, known, checks, limits.deadline)
        parents = parents[: checked.size]
        new = np.arange(count, count + checked.size)[checked]
        small, large = sorted(parts, key=lambda part: part.size)
        candidates = np.vstack(
            [
                parent_pairs(new, parents[checked], grown.states, reach=self.reach),
                nearest_pairs(grown.states, new, grown.usable, neighbours=self.settings.neighbours, reach=self.reach),
                bridge_pairs(grown.states, small, large, count=self.settings.bridges, reach=self.reach),
            ]
        )
        pairs, motions = straight_motions(
            grown.states, new_pairs(candidates, grown.edges), connector=self.connector, sampler=self.sampler
        )
        grown.add_edges(pairs, motions)
        return True

    def _check_states(
        self,
        states: FloatArray,
        oracle: MotionOracle,
        known: dict[int, bool],
        checks: list[CheckRecord],
        deadline: float | None,
    ) -> BoolArray:
        """Add the states as vertices and check each (its vertex edge, logged); (N',) free flags of the checked.

        Stops at the deadline: the states after it are not added (N' <= N).
        """
        free: list[bool] = []
        for state in states:
            if deadline is not None and time.perf_counter() >= deadline:
                break
            vertex, edge = (int(x[0]) for x in self.grown.add_vertices(state[None]))
            ok = self._logged_check(edge, oracle, known, checks)
            free.append(ok)
            if ok:
                self.grown.mark_free(np.array([vertex]))
        return np.array(free, dtype=bool)
