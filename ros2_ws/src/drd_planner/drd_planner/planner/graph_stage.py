"""The plan's stages after the library: the lazy search over the whole graph, then growth.

When every library path is blocked (or a new query's lead proved the graph has no free path), the planner
goes on with LazySP over the query's whole graph from every outcome known (:func:`~drd_planner.planner.
roadmap_growth.lazy_search`, the weights of :mod:`~drd_planner.planner.graph_fallback`); when the graph has
no free path, a domain that samples valid states grows its roadmap and a connector that ranks more joins
gives an off-graph start or goal more of them, each checked lazily, until a path is verified or the growth's
budget ends. :class:`GraphStage` runs these for one plan and says why no path was proven when none was.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from drd_planner.core.episode import CheckRecord, EdgeOracle, append_episode
from drd_planner.core.status import PlanCause
from drd_planner.planner.anytime import PlanLimits
from drd_planner.planner.connect import MotionOracle, QueryConnector
from drd_planner.planner.growth_samples import SegmentMaker
from drd_planner.planner.join_growth import JoinGrowth, more_joins_of
from drd_planner.planner.no_path import blocked_end, edge_states_of, no_path_reason
from drd_planner.planner.prior import WorldPrior
from drd_planner.planner.query_graph import MotionDispatch
from drd_planner.planner.query_model import QueryModel
from drd_planner.planner.query_models import QueryModels
from drd_planner.planner.result import (
    PlanResult,
    PlanStage,
    PlanStatus,
    exhausted_result,
    found_result,
    unproven_result,
)
from drd_planner.planner.roadmap_growth import GraphGrowth, GrowthSettings, RoadmapGrowth, lazy_search
from drd_planner.planner.state_sampler import sampler_of

__all__ = ["GraphStage", "PlanSoFar", "unwrapped_oracle"]


def unwrapped_oracle(oracle: EdgeOracle) -> EdgeOracle:
    """The oracle a connected query's :class:`MotionDispatch` wraps (the oracle itself otherwise)."""
    return oracle.oracle if isinstance(oracle, MotionDispatch) else oracle


@dataclass(frozen=True)
class PlanSoFar:
    """A plan as the graph stage takes it over.

    Attributes:
        model: the query's model (its graph is searched).
        oracle: the plan's oracle.
        known: every outcome of the plan so far (edge id -> free); the stages extend it.
        checks: the plan's check log; the stages extend it.
        limits: the plan's seed and budgets.
        times: when the query's model was ready and when the plan began (``time.perf_counter()``).
    """

    model: QueryModel
    oracle: EdgeOracle
    known: dict[int, bool]
    checks: list[CheckRecord]
    limits: PlanLimits
    times: tuple[float, float]


class GraphStage:
    """The graph stage and growth of one plan (see the module docstring).

    Args:
        prior: the planner's prior (its current setting).
        connector: the planner's connector (None: off-graph states refused, no growth of joins).
        growth: the growth's budget (None: the graph never grows).
        models: the planner's query models (the points along edges and the packed training columns).
    """

    def __init__(
        self,
        prior: WorldPrior,
        connector: QueryConnector | None,
        growth: GrowthSettings | None,
        models: QueryModels,
    ) -> None:
        self.prior, self.growth = prior, growth
        self._connector, self._models = connector, models

    def run(self, plan: PlanSoFar) -> PlanResult:
        """The graph stage after the library, then roadmap growth: its result, or why no path was proven."""
        model, checks, limits = plan.model, plan.checks, plan.limits
        t_model, t_begin = plan.times
        raw, report = unwrapped_oracle(plan.oracle), None
        kind = self.growth_kind(model) if isinstance(raw, MotionOracle) else None
        first = None if kind is None or not kind.starts_early or self.growth is None else self.growth.graph_checks_first
        stage = self._lazy_stage(plan, first)
        if isinstance(stage, PlanResult):
            return stage
        growth = None if kind is None else self.growth_of(model, kind)
        if growth is not None and isinstance(raw, MotionOracle):
            grown = growth.run(
                raw, plan.known, checks, seed=limits.seed, max_checks=limits.max_checks, deadline=limits.deadline
            )
            report = grown.report
            if grown.status is PlanStatus.FOUND and grown.path_edges is not None:
                return found_result(model, grown.path_edges, checks, PlanStage.GROW, plan.times, report)
            if grown.cause is not None and grown.cause.is_budget:
                return exhausted_result(model, grown.cause, checks, t_model, t_begin, report)
        if stage:  # growth began before the graph stage's proof: finish it (every outcome reused)
            finished = self._lazy_stage(plan, None)
            if isinstance(finished, PlanResult):
                return finished
        query = model.query if report is None else report.query
        along = edge_states_of(self.prior, query, getattr(self._connector, "segment", None))
        reason = no_path_reason(query, checks, raw, along, report)
        result = unproven_result(model, PlanStatus.NO_PATH, reason, checks, t_model, t_begin, report)
        return dataclasses.replace(result, cause=blocked_end(query, checks))

    def _lazy_stage(self, plan: PlanSoFar, first: int | None) -> PlanResult | bool:
        """The lazy search over the query's whole graph, reusing and extending the plan's outcomes and checks.

        Args:
            plan: the plan so far (its ``known`` and ``checks`` are extended).
            first: checks at most before the stage stops for growth to begin (None: until it ends).

        Returns:
            The plan's result when it found a path or one of the plan's budgets ended; True when it stopped
            after ``first`` checks without either; False when it proved that the graph has no free path.
        """
        model, known, checks, limits = plan.model, plan.known, plan.checks, plan.limits
        t_model, t_begin = plan.times
        budget = None if limits.max_checks is None else limits.max_checks - len(checks)
        if budget is not None and budget <= 0:
            return exhausted_result(model, PlanCause.CHECK_BUDGET, checks, t_model, t_begin)
        stage_budget = budget if first is None else (first if budget is None else min(first, budget))
        edges = model.query.graph.num_edges  # outcomes of a growth's new edges (ids from E on) are not this graph's
        usable = known if all(e < edges for e in known) else {e: f for e, f in known.items() if e < edges}
        episode = lazy_search(
            self.prior, model.query, plan.oracle, usable, budget=stage_budget, deadline=limits.deadline, stage="graph"
        )
        append_episode(checks, known, episode)
        if episode.success and episode.path_edges is not None:
            return found_result(model, episode.path_edges, checks, PlanStage.GRAPH, plan.times)
        if episode.ran_out is PlanCause.CHECK_BUDGET and stage_budget != budget:
            return True
        if episode.ran_out is not None:
            return exhausted_result(model, episode.ran_out, checks, t_model, t_begin)
        return False

    def growth_kind(self, model: QueryModel) -> type[GraphGrowth] | None:
        """How the query's graph grows when it has no free path (None: it does not, or growth is off).

        A domain that samples valid states grows its roadmap (the arm); a connector that can join a state to
        more vertices gives an off-graph start or goal more joins (the helicopter).
        """
        if self.growth is None or model.query.graph.vertex_states is None:
            return None
        if sampler_of(self._connector) is not None and isinstance(self._connector, SegmentMaker):
            return RoadmapGrowth
        if more_joins_of(self._connector) is not None and model.query.connected:
            return JoinGrowth
        return None

    def growth_of(self, model: QueryModel, kind: type[GraphGrowth]) -> GraphGrowth | None:
        """The growth of ``kind`` (:meth:`growth_kind`) for the query."""
        sampler, joins, settings = sampler_of(self._connector), more_joins_of(self._connector), self.growth
        if settings is None:
            return None
        index = self._models.sample_index()
        if kind is RoadmapGrowth and sampler is not None and isinstance(self._connector, SegmentMaker):
            return RoadmapGrowth(self.prior, model.query, self._connector, sampler, index, settings)
        if kind is JoinGrowth and joins is not None:
            return JoinGrowth(self.prior, model.query, joins, index, settings, self._models.columns)
        return None
