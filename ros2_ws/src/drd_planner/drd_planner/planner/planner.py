"""One planning API, ROS-free: any (start, goal) of a prior's graph, checked against any edge oracle.

A plan runs in up to two stages, all checks going through the one episode runner
(:func:`~drd_planner.core.episode.run_episode`), which returns a path only when every edge of it was
checked free in this plan:

0. **the probe**, on a new query (vertices, or states joined by motions; no precomputed tree): its
   union path (the shortest over the edges free in any training world), checked first when the training worlds
   say it is free with probability at least ``probe_probability`` (one half); the library is built only if an
   edge of it is blocked, and the library stage then knows that outcome (:mod:`~drd_planner.planner.probe`).
   Told what one check costs (:attr:`Planner.check_cost_ms`), such a query then runs **the lead**: the lazy
   search of stage 2 for at most as many checks as its library would cost, and builds the library only if
   that verified no path (:mod:`~drd_planner.planner.lead`).
1. **the library stage**: the query's path library with a policy (default ``direct_bisect``: the
   DiRECt tree, then BiSECt). A query with a precomputed tree uses that tree and its library unchanged;
   any other query gets a library built online from the prior's training worlds
   (:mod:`~drd_planner.planner.query_library`) and a DiRECt tree grown along the branch taken
   (:class:`~drd_planner.core.online_tree.LazyDirectTree`; BiSECt from the root when the switch threshold is
   1). Both are cached per query (LRU), and what does not depend on the query is built once per prior
   (:mod:`~drd_planner.planner.query_models`).
2. **the graph stage**, when every library path is blocked: lazy search over the whole graph with the
   prior's edge probabilities (:mod:`~drd_planner.planner.graph_fallback`), reusing every check made
   (:mod:`~drd_planner.planner.graph_stage`, with growth).
3. **growth**, when the graph has no free path: a domain that samples its valid states (the arm) gets new
   vertices and edges where the blocked region cuts the graph (:mod:`~drd_planner.planner.roadmap_growth`);
   an off-graph start or goal whose connector ranks more joins (the helicopter) gets more of them
   (:mod:`~drd_planner.planner.join_growth`); each checked lazily, the graph search again, until a path is
   verified or the growth budget ends. More joins begin already when the graph stage has made
   ``graph_checks_first`` checks (64) without a path; the graph stage's proof is finished after them when they
   found none.

With ``improve_budget`` a plan then seeks shorter verified paths (:mod:`~drd_planner.planner.anytime`).
So the planner says "no path" only when the graph has none given the checks made (and growth found none
within its budget); the reason names the start and goal and what blocks them
(:mod:`~drd_planner.planner.no_path`). A check or time budget ends a plan with its own status.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Any

from drd_planner.arrays import FloatArray
from drd_planner.core.episode import EdgeOracle, EpisodeResult, append_episode, run_episode
from drd_planner.core.lazysp import SELECTORS, lazysp_name
from drd_planner.core.policies import CORE_POLICIES, POLICIES, TREE_POLICIES, PolicyContext
from drd_planner.core.region_rule import check_region_rule
from drd_planner.core.tree import DEFAULT_EXPAND_THRESHOLD
from drd_planner.exceptions import ProblemError
from drd_planner.planner.anytime import ImproveBudget, PlanLimits, as_improve_budget, check_budgets, improve_path
from drd_planner.planner.blas_threads import one_blas_thread
from drd_planner.planner.connect import MotionOracle, QueryConnector, connector_for
from drd_planner.planner.endpoints import Endpoint, EndpointResolver, QueryError
from drd_planner.planner.graph_stage import GraphStage, PlanSoFar, unwrapped_oracle
from drd_planner.planner.lead import before_library, check_cost, lead_checks
from drd_planner.planner.prior import LeafSetting, WorldPrior
from drd_planner.planner.probe import DEFAULT_PROBE_PROBABILITY, PROBE_POLICIES, check_probe_probability
from drd_planner.planner.query_graph import MotionDispatch, QueryGraph, connected_query, prior_query
from drd_planner.planner.query_model import QueryModel
from drd_planner.planner.query_models import DEFAULT_CACHE_SIZE, QueryModels
from drd_planner.planner.result import (
    PlanResult,
    PlanStatus,
    exhausted_result,
    found_result,
    library_stage,
    plan_timings,
    trivial_result,
)
from drd_planner.planner.roadmap_growth import (
    DEFAULT_GROWTH,
    GrowthSettings,
)
from drd_planner.planner.state_sampler import sampler_of

#: Library-stage policies :meth:`Planner.plan` accepts: every registered library policy but
#: ``direct_only`` (it needs an offline tree) and the full-graph LazySP family (not library policies).
PLAN_POLICIES = tuple(sorted(set(CORE_POLICIES) - {"direct_only", *(lazysp_name(s) for s in SELECTORS)}))


class Planner:
    """Plans any query of one :class:`WorldPrior` against an edge oracle.

    Args:
        prior: the graph, its training worlds and precomputed trees.
        cache_size: queries whose library and tree are kept.
        snap_tolerance: how far a state may lie from its vertex (state units); None: a quarter of the
            median edge length.
        expand_threshold: online trees expand a node only while its fraction is at least this.
        connector: joins off-graph states to the graph (None: the prior domain's, :data:`CONNECTORS`).
        connect_states: False refuses off-graph states (no connector).
        growth: how far the graph grows when it has no free path (None: never); only with a connector that
            has a sampler of valid states (the arm's) and an oracle that checks motions.
        probe_probability: a new query first checks its union path when that is free with at least this
            probability over the training worlds (:mod:`~drd_planner.planner.probe`); None: never.

    Set :attr:`check_cost_ms` when you know what one check costs: a new query then first runs a lazy search
    for as many checks as its library would cost (:mod:`~drd_planner.planner.lead`).
    """

    def __init__(
        self,
        prior: WorldPrior,
        *,
        cache_size: int = DEFAULT_CACHE_SIZE,
        snap_tolerance: float | None = None,
        expand_threshold: float = DEFAULT_EXPAND_THRESHOLD,
        connector: QueryConnector | None = None,
        connect_states: bool = True,
        growth: GrowthSettings | None = DEFAULT_GROWTH,
        probe_probability: float | None = DEFAULT_PROBE_PROBABILITY,
    ) -> None:
        self.prior = prior
        self._connector = (connector or connector_for(prior)) if connect_states else None
        free = getattr(self._connector, "free_goal_dims", ())
        self._endpoints = EndpointResolver(prior.graph, snap_tolerance=snap_tolerance, free_goal_dims=free)
        self._models = QueryModels(prior, self._connector, cache_size=cache_size, expand_threshold=expand_threshold)
        self._models.probe_probability = check_probe_probability(probe_probability)
        self._models.price_stage = self._price_stage
        self._check_cost_ms: float | None = None
        self._leaf_override: LeafSetting | None = None
        self.growth = growth

    @classmethod
    def from_file(cls, path: str | Path, *, expected_domain: str | None = None, **options: Any) -> Planner:
        """A planner over the prior (or tree) file at ``path`` (see :func:`drd_planner.planner.load_prior`).

        ``options`` are the constructor's keyword arguments.
        """
        from drd_planner.planner.prior_file import load_prior

        return cls(load_prior(path, expected_domain=expected_domain), **options)

    @property
    def check_cost_ms(self) -> float | None:
        """What one check costs in CPU milliseconds (None, the default: unknown, so no lead).

        Set it (a finite number >= 0; ProblemError otherwise) and a new query first runs a lazy search for at
        most :meth:`lead_checks` checks before its library is built (:mod:`~drd_planner.planner.lead`).
        """
        return self._check_cost_ms

    @check_cost_ms.setter
    def check_cost_ms(self, value: float | None) -> None:
        self._check_cost_ms = check_cost(value, "check_cost_ms")
        self._models.library_waits = self._check_cost_ms is not None

    def library_cost_ms(self, *, joined: bool = False) -> float:
        """What buying a new query's library costs in CPU ms (built, and its stage's selections): the lead's price.

        Measured once per kind of query on this machine (between vertices, or ``joined``: a start or goal off
        the graph; at :meth:`warm_up` when :attr:`check_cost_ms` is set, else on first need) unless fixed by
        :meth:`set_library_cost_ms`.
        """
        return self._models.library_cost_ms(joined=joined)

    def lead_check_ms(self, *, joined: bool = False) -> float:
        """The lead's own CPU per check in milliseconds, beside the check's cost (measured with its price)."""
        return self._models.lead_check_ms(joined=joined)

    def set_library_cost_ms(self, value: float | None, *, lead_check_ms: float = 0.0) -> None:
        """Fix the lead's price for every query (None: measure it); the same budget on every machine and run.

        Args:
            value: what a new query's library costs in CPU ms (:meth:`library_cost_ms`), or None.
            lead_check_ms: the lead's own CPU per check in ms while the price is fixed (:meth:`lead_check_ms`).

        Raises:
            ProblemError: a value that is not a finite number >= 0, or a ``lead_check_ms`` without a ``value``.
        """
        own = check_cost(lead_check_ms, "lead_check_ms")
        if value is None and own:
            raise ProblemError("lead_check_ms is fixed with the library cost: give value too (None measures both)")
        self._models.fixed_library_cost_ms = check_cost(value, "library_cost_ms")
        self._models.fixed_lead_check_ms = 0.0 if own is None else own

    def lead_checks(self, *, joined: bool = False) -> int | None:
        """A new query's lead budget in checks (0: no lead; None: no limit).

        0 while :attr:`check_cost_ms` is None, else ``floor(library_cost_ms(joined) / (check_cost_ms +
        lead_check_ms(joined)))``: the checks the lead can make, each costing C and its own search, for what the
        library would cost (no limit when both are 0).
        """
        if self._check_cost_ms is None:
            return 0
        models = self._models
        return lead_checks(
            self._check_cost_ms, models.library_cost_ms(joined=joined), models.lead_check_ms(joined=joined)
        )

    @property
    def snap_tolerance(self) -> float:
        """How far a state may lie from the vertex it snaps to, in state units."""
        return self._endpoints.snap_tolerance

    def set_leaf(self, eta: float, pseudo_count: float | None, *, region_rule: str | None = None) -> None:
        """Use this switch threshold and leaf pseudo-count for every query from the next plan on.

        It overrides the prior's setting and the precomputed trees' own; the cache stays valid. A new
        ``region_rule`` (None: keep), or eta moving to or from 1 (BiSECt from the root or a DiRECt tree grown
        online), drops the cached online trees; precomputed trees keep their own rule.

        Raises:
            ProblemError: eta outside (0, 1], a pseudo-count that is not positive, or an unknown rule.
        """
        rule = check_region_rule(region_rule or self.prior.region_rule)
        self._leaf_override = LeafSetting(eta, pseudo_count)
        if rule != self.prior.region_rule or (eta >= 1.0) != (self.prior.eta >= 1.0):
            self._models.drop_online()  # their trees were built for the old rule or switch threshold
        self.prior = dataclasses.replace(self.prior, eta=eta, pseudo_count=pseudo_count, region_rule=rule)
        self._models.prior = self.prior

    def leaf(self, model: QueryModel) -> LeafSetting:
        """The eta and kappa of a query's library stage.

        Set by :meth:`set_leaf`, else its precomputed tree's own (:attr:`QueryTree.leaf`), else the prior's.
        """
        return self._leaf_override or self.prior.leaf_for(model.precomputed)

    @property
    def endpoints(self) -> EndpointResolver:
        """How this planner reads starts and goals (ids, states, free goal dimensions)."""
        return self._endpoints

    @property
    def connector(self) -> QueryConnector | None:
        """What joins off-graph states to the graph (None: such states are refused)."""
        return self._connector

    def resolve(self, start: Endpoint, goal: Endpoint) -> tuple[int, int]:
        """Vertex ids of a start and goal given as ids or states within the snap tolerance.

        Raises:
            QueryError: either is malformed or farther than the snap tolerance.
        """
        return self._endpoints.resolve(start, "start"), self._endpoints.resolve(goal, "goal")

    def cached_queries(self) -> list[tuple[object, object]]:
        """The (start, goal) pairs in the cache, least recently used first."""
        return self._models.cached_queries()

    def warm_up(self) -> None:
        """Do the per-prior work of new queries now (packed worlds, search worlds), not in the first one."""
        self._models.warm_up()

    def forget_queries(self) -> None:
        """Forget past queries, so that the next plan of any query is new.

        Drops the libraries and trees built online and the reverse search trees kept for past goals. The
        per-prior work (:meth:`warm_up`) and the precomputed trees stay. Benchmarks call it so that every
        policy pays a new query's library and tree itself.
        """
        self._models.forget_queries()

    @one_blas_thread
    def query_graph(self, start: Endpoint, goal: Endpoint) -> QueryGraph:
        """The graph a query plans over, without its library or imputed training outcomes.

        The prior's graph, plus a new vertex per off-graph state and the connector's motions joining it.
        What a graph-search peer (LazySP, checking everything) plans on; :meth:`plan` builds the same joins.

        Raises:
            QueryError: a state that cannot be joined (no connector, or no vertex within its reach).
        """
        s = self._endpoints.snap(start, "start")
        g = self._endpoints.snap(goal, "goal")
        if isinstance(s, int) and isinstance(g, int):
            return prior_query(self.prior, s, g, None)
        connector = self._require_connector()
        return connected_query(self.prior, s, g, connector, self._models.sample_index(), None)

    def memory_bytes(self) -> dict[str, int]:
        """Approximate memory of the prior's arrays and of the cached query libraries, in bytes."""
        prior = self.prior
        worlds = 0 if prior.worlds is None else int(prior.worlds.nbytes)
        graph = int(prior.graph.edges.nbytes + prior.graph.lengths.nbytes)
        trees = sum(int(qt.tree.free_fraction.nbytes + qt.tree.edge.nbytes * 6) for qt in prior.trees)
        return {"worlds": worlds, "graph": graph, "trees": trees, "query_cache": self._models.cached_bytes()}

    def query_model(self, start: int | FloatArray, goal: int | FloatArray) -> QueryModel:
        """The library and tree of the query (from the cache, a precomputed tree, or built now).

        ``start`` and ``goal`` are vertex ids, or validated states off the graph (joined by motions).

        Raises:
            QueryError: the prior holds training worlds only for its precomputed queries, or a state
                has no vertex within the connector's reach.
        """
        return self._models.get(start, goal)

    def _require_connector(self) -> QueryConnector:
        if self._connector is None:
            raise QueryError(
                f"a state farther than the snap tolerance {self.snap_tolerance:.4g} from every vertex needs a "
                f"connector, and domain {self.prior.domain!r} has none: give vertex ids or nearer states"
            )
        return self._connector

    @one_blas_thread
    def plan(
        self,
        start: Endpoint,
        goal: Endpoint,
        oracle: EdgeOracle,
        *,
        seed: int = 0,
        max_checks: int | None = None,
        time_budget_s: float | None = None,
        policy: str = "direct_bisect",
        improve_budget: ImproveBudget | int | None = None,
    ) -> PlanResult:
        """Find a path from ``start`` to ``goal`` whose every edge ``oracle`` says is free.

        Args:
            start: a vertex id, or a (d,) state that snaps to the nearest vertex.
            goal: likewise.
            oracle: answers ``check(edge) -> bool`` (a row of X in benchmarks, FCL in the node).
            seed: seed of the policy's random choices (same seed, same checks).
            max_checks: the most checks this plan may make (None: no limit).
            time_budget_s: the most seconds of this plan (None: no limit); checked before each selection.
            policy: the library stage's policy (:data:`PLAN_POLICIES`).
            improve_budget: after the first verified path, look for shorter ones within this budget
                (:mod:`~drd_planner.planner.anytime`; an int n is ``ImproveBudget(checks=n)``); None: stop
                at the first path. Its checks count against ``max_checks`` too.

        Returns:
            The result; REFUSED (never an exception) for a malformed or unreachable start or goal.

        Raises:
            ProblemError: an unknown policy, or a budget that is not positive.
        """
        t_begin = time.perf_counter()
        _check_plan_arguments(policy, max_checks, time_budget_s)
        improve = as_improve_budget(improve_budget)
        deadline = None if time_budget_s is None else t_begin + float(time_budget_s)
        try:
            resolved = self._resolve(start, goal, oracle)
        except QueryError as exc:
            return PlanResult(PlanStatus.REFUSED, str(exc), timings=plan_timings((), 0.0, t_begin), cause=exc.cause)
        if isinstance(resolved, int):
            return trivial_result(resolved, t_begin)
        model = resolved
        if model.query.connected:
            oracle = MotionDispatch(oracle, model.query.motions)  # type: ignore[arg-type]
        t_model = time.perf_counter() - t_begin
        limits = PlanLimits(seed, max_checks, deadline)
        result = self._search(model, oracle, policy, limits, (t_model, t_begin))
        if improve is None or not result.found:
            return result
        if result.growth is not None:  # improve on the grown graph
            model = dataclasses.replace(model, query=result.growth.query)
            raw = unwrapped_oracle(oracle)
            assert isinstance(raw, MotionOracle)  # growth checks its edges with check_motion
            oracle = MotionDispatch(raw, result.growth.query.motions)
        return improve_path(result, model, oracle, improve, prior=self.prior, limits=limits)

    def _search(
        self,
        model: QueryModel,
        oracle: EdgeOracle,
        policy: str,
        limits: PlanLimits,
        times: tuple[float, float],
    ) -> PlanResult:
        """The library stage, then the graph stage when every library path is blocked (then growth)."""
        t_model, t_begin = times
        lead = self.lead_checks(joined=model.query.connected) if policy in PROBE_POLICIES else 0
        ahead = before_library(self.prior, model, oracle, policy, limits, lead)
        checks, known = ahead.checks, ahead.known
        if ahead.stage is not None and ahead.path_edges is not None:
            return found_result(model, ahead.path_edges, checks, ahead.stage, times)
        if ahead.ran_out is not None:
            return exhausted_result(model, ahead.ran_out, checks, t_model, t_begin)
        if ahead.no_path:  # the lead proved it: no library can find a path either
            return self._graph_stage().run(PlanSoFar(model, oracle, known, checks, limits, times))
        if model.library_pending:  # after the probe and lead (or another policy): the library now, timed as such
            model = self._models.with_library(model)
            t_model, times = t_model + model.build_s, (t_model + model.build_s, t_begin)
        if model.library is not None:
            episode = self._library_episode(model, oracle, policy, limits, known, len(checks))
            append_episode(checks, known, episode)
            if episode.success and episode.path_edges is not None:
                return found_result(model, episode.path_edges, checks, library_stage(checks), times)
            if episode.ran_out is not None:  # a policy that gave up goes on to the graph, as a blocked library
                return exhausted_result(model, episode.ran_out, checks, t_model, t_begin)
        return self._graph_stage().run(PlanSoFar(model, oracle, known, checks, limits, times))

    def _library_episode(
        self, model: QueryModel, oracle: EdgeOracle, policy: str, limits: PlanLimits, known: dict[int, bool], used: int
    ) -> EpisodeResult:
        """The library stage's episode (the library built), told ``known`` (the ``used`` checks before it)."""
        assert model.library is not None
        lib_policy = POLICIES[policy](self._context(model, policy, limits.seed))
        for edge, free in known.items():  # the probe's and the lead's outcomes
            lib_policy.observe(edge, free)
        budget = None if limits.max_checks is None else limits.max_checks - used
        costs = model.query.edge_costs
        return run_episode(
            model.library, costs, lib_policy, oracle, max_checks=budget, deadline=limits.deadline, known=known
        )

    def _price_stage(self, model: QueryModel, oracle: EdgeOracle) -> None:
        """The library stage of the method's policy, to a path or its end (what the lead's price times)."""
        self._library_episode(model, oracle, "direct_bisect", PlanLimits(0, None, None), {}, 0)

    def _resolve(self, start: Endpoint, goal: Endpoint, oracle: EdgeOracle) -> QueryModel | int:
        """The query's model, or the one vertex when start and goal snap to it (QueryError: refused)."""
        s = self._endpoints.snap(start, "start")
        g = self._endpoints.snap(goal, "goal")
        if isinstance(s, int) and isinstance(g, int) and s == g:
            return s
        if not (isinstance(s, int) and isinstance(g, int)):
            self._require_connector()
            if not isinstance(oracle, MotionOracle):
                raise QueryError(
                    "an off-graph start or goal is joined by new motions, and this oracle cannot check "
                    "them (it needs check_motion(states)); give vertex ids or states within the snap "
                    f"tolerance {self.snap_tolerance:.4g}"
                )
            sampler = sampler_of(self._connector)
            for label, value in (("start", s), ("goal", g)):
                why = None if sampler is None or isinstance(value, int) else sampler.refusal(value, label)
                if why:
                    raise QueryError(why)
        return self.query_model(s, g)

    def _graph_stage(self) -> GraphStage:
        """The graph stage and growth of a plan, with the planner's current prior and growth budget."""
        return GraphStage(self.prior, self._connector, self.growth, self._models)

    def _context(self, model: QueryModel, policy: str, seed: int) -> PolicyContext:
        assert model.library is not None
        prior = self.prior
        leaf = self.leaf(model)
        return PolicyContext(
            library=model.library,
            edge_costs=model.query.edge_costs,
            train_theta=model.theta,
            tree=model.tree if policy in TREE_POLICIES else None,
            seed=seed,
            eta=leaf.eta,
            alpha=prior.alpha,
            pseudo_count=leaf.pseudo_count,
            graph=model.query.graph,
            start=model.start,
            goal=model.goal,
        )


def _check_plan_arguments(policy: str, max_checks: int | None, time_budget_s: float | None) -> None:
    """ProblemError for an unknown policy or a budget that is not positive."""
    if policy not in PLAN_POLICIES:
        raise ProblemError(f"unknown planning policy {policy!r}; known: {', '.join(PLAN_POLICIES)}")
    check_budgets(max_checks, time_budget_s)
