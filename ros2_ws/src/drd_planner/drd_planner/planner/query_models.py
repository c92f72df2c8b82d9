"""Every query's library and tree from one prior: what is per prior is built once, what is per query is cached.

:class:`QueryModels` is where :class:`~drd_planner.planner.Planner` gets a query's
:class:`~drd_planner.planner.query_model.QueryModel`: the precomputed tree's for a stored query, else one built
now and kept (least recently used dropped first). The work that does not depend on the query is done once per
prior, on first need (or at :meth:`QueryModels.warm_up`):

- the packed columns of the training worlds (:class:`~drd_planner.core.world_columns.WorldColumns`: the
  posterior's counts in milliseconds);
- the search worlds and their block graph (:class:`~drd_planner.planner.goal_trees.SearchWorlds`: distinct
  worlds found once, the libraries' searches batched and their trees kept per goal);
- the graph's arcs and the points along its edges that impute the outcomes of new motions;
- when the planner is told what a check costs, what a new query's library costs and what each check of the lead
  costs it (:meth:`QueryModels.library_cost_ms`, :meth:`QueryModels.lead_check_ms`: the price of
  :mod:`~drd_planner.planner.lead`).

A query whose switch threshold is 1 (validation picks it for new queries on every shipped prior: BiSECt from
the root) gets a :class:`~drd_planner.core.root_tree.RootTree` instead of a DiRECt tree grown online.
"""

from __future__ import annotations

import dataclasses
import time
from collections import OrderedDict
from collections.abc import Callable

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.core.bisect import bias_from_worlds
from drd_planner.core.episode import EdgeOracle, TableOracle
from drd_planner.core.lazysp import GraphArcs
from drd_planner.core.online_tree import LazyDirectTree
from drd_planner.core.root_tree import RootTree
from drd_planner.core.tree import TreeNodes
from drd_planner.core.world_columns import WorldColumns
from drd_planner.exceptions import ProblemError
from drd_planner.planner.connect import EdgeSampleIndex, QueryConnector
from drd_planner.planner.endpoints import QueryError
from drd_planner.planner.goal_trees import SearchWorlds
from drd_planner.planner.prior import WorldPrior
from drd_planner.planner.probe import Probe, union_probe
from drd_planner.planner.query_graph import QueryGraph, connected_query, prior_query
from drd_planner.planner.query_library import query_library
from drd_planner.planner.query_model import QueryModel
from drd_planner.planner.roadmap_growth import lazy_search

__all__ = ["DEFAULT_CACHE_SIZE", "QueryModels"]

#: Queries whose library and tree are kept (least recently used dropped first).
DEFAULT_CACHE_SIZE = 16
#: Random queries (of each kind) whose library is timed for :meth:`QueryModels.library_cost_ms`.
LIBRARY_COST_QUERIES = 9
#: The most checks of the lead timed on each of them (:meth:`QueryModels.lead_check_ms`).
LEAD_COST_CHECKS = 50


class QueryModels:
    """The query models of one prior (see the module docstring).

    Args:
        prior: the prior (its setting may be replaced later: :attr:`prior` is read at each build).
        connector: joins off-graph states (None: they are refused).
        cache_size: queries kept.
        expand_threshold: online DiRECt trees expand a node only while its fraction is at least this.
    """

    def __init__(
        self,
        prior: WorldPrior,
        connector: QueryConnector | None,
        *,
        cache_size: int = DEFAULT_CACHE_SIZE,
        expand_threshold: float,
    ) -> None:
        if cache_size < 1:
            raise ProblemError(f"cache_size must be at least 1, got {cache_size}")
        #: A new query whose union path is free with at least this probability gets a probe, and its
        #: library only when the probe needs it (:mod:`~drd_planner.planner.probe`); None: never.
        self.probe_probability: float | None = None
        #: A new query's library waits until a plan needs it (after the lead: :mod:`~drd_planner.planner.lead`).
        self.library_waits = False
        #: The lead's library price in CPU ms when given (None: :meth:`library_cost_ms` measures it).
        self.fixed_library_cost_ms: float | None = None
        #: The lead's own CPU per check in ms while the price is fixed (:meth:`lead_check_ms`).
        self.fixed_lead_check_ms = 0.0
        self._library_cost_ms: dict[bool, tuple[float, float]] = {}
        #: Runs a built model's library stage to its end (the planner's; timed in the lead's price), or None.
        self.price_stage: Callable[[QueryModel, EdgeOracle], None] | None = None
        self.prior = prior
        self.connector = connector
        self._cache: OrderedDict[tuple[object, object], QueryModel] = OrderedDict()
        self._cache_size = cache_size
        self._expand = expand_threshold
        self._arcs: GraphArcs | None = None
        self._columns: WorldColumns | None = None
        self._search: SearchWorlds | None = None
        self._index: EdgeSampleIndex | None = None

    # ------------------------------------------------------------------------------------------------
    # Per prior, once

    @property
    def arcs(self) -> GraphArcs:
        """The prior graph's arcs."""
        if self._arcs is None:
            self._arcs = GraphArcs(self.prior.graph)
        return self._arcs

    @property
    def columns(self) -> WorldColumns | None:
        """The training worlds' packed columns (None for a prior without worlds over every edge)."""
        if self._columns is None and self.prior.worlds is not None:
            self._columns = WorldColumns(self.prior.worlds)
        return self._columns

    @property
    def search(self) -> SearchWorlds:
        """The search worlds of the online libraries."""
        if self._search is None:
            assert self.prior.worlds is not None
            self._search = SearchWorlds(
                self.arcs, self.prior.graph.lengths, self.prior.worlds, seed=self.prior.library_seed
            )
        return self._search

    def sample_index(self) -> EdgeSampleIndex:
        """Points along every graph edge, for the imputed outcomes of new motions.

        Raises:
            QueryError: there is no connector (no motions to impute).
        """
        if self.connector is None:
            raise QueryError("this planner has no connector: states off the graph are refused")
        if self._index is None:
            self._index = EdgeSampleIndex(
                self.prior.graph, self.prior.edge_trajectories, position_dims=self.connector.position_dims
            )
        return self._index

    def warm_up(self) -> None:
        """Build the per-prior work now (a node does it at configure, not in its first new request).

        That includes the reverse trees of the precomputed queries' goals: a robot that leaves the stored
        route (a start off the graph, a replan from a vertex the tree was not built for) asks for them first.
        """
        _ = self.arcs, self.columns
        if self.prior.worlds is not None:
            _ = self.search, self.prior.edge_marginal
            if self.library_waits:
                self.library_cost_ms()
                self.library_cost_ms(joined=True)
            for qt in self.prior.trees:
                self.search.tree(qt.goal)
        if self.connector is not None and self.prior.graph.vertex_states is not None:
            self.sample_index()

    # ------------------------------------------------------------------------------------------------
    # Per query, cached

    def get(self, start: int | FloatArray, goal: int | FloatArray) -> QueryModel:
        """The query's model (from the cache, a precomputed tree, or built now).

        Raises:
            QueryError: the prior holds training worlds only for its precomputed queries, or a state
                cannot be joined to the graph.
        """
        key = (_cache_key(start), _cache_key(goal))
        if key in self._cache:
            self._cache.move_to_end(key)
            return dataclasses.replace(self._cache[key], reused=True)
        model = self._build(start, goal)
        self._cache[key] = model
        while len(self._cache) > self._cache_size:
            self._cache.popitem(last=False)
        return model

    def cached_queries(self) -> list[tuple[object, object]]:
        """The (start, goal) keys in the cache, least recently used first."""
        return list(self._cache)

    def cached_models(self) -> list[QueryModel]:
        """The cached models, least recently used first."""
        return list(self._cache.values())

    def cached_bytes(self) -> int:
        """Approximate memory of the cached libraries and online trees, in bytes."""
        total = 0
        for model in self._cache.values():
            if model.library is not None:
                total += sum(int(p.nbytes) * 2 for p in model.library.path_edges)
                total += int(model.library.incidence.data.nbytes) * 3
            if isinstance(model.tree, LazyDirectTree):
                total += model.tree.num_worlds * (model.library.num_paths if model.library else 0) * 8
        return total

    def forget_queries(self) -> None:
        """Drop the online models and the goal trees kept for past goals: every next query is new."""
        self.drop_online()
        if self._search is not None:
            self._search.forget_trees()

    def drop_online(self) -> None:
        """Forget the models built online (their tree or library settings changed); precomputed ones stay."""
        self._cache = OrderedDict((k, m) for k, m in self._cache.items() if m.precomputed is not None)

    def _build(self, start: int | FloatArray, goal: int | FloatArray) -> QueryModel:
        t0 = time.perf_counter()
        prior = self.prior
        qt = prior.tree_for(start, goal) if isinstance(start, int) and isinstance(goal, int) else None
        if qt is not None:
            theta = prior.edge_marginal if prior.worlds is not None else qt.tree.bias(0, alpha=prior.alpha)
            query = prior_query(prior, qt.start, qt.goal, self.columns)
            return QueryModel(query, qt.library, qt.tree, theta, f"tree:{qt.name}", time.perf_counter() - t0, qt)
        if prior.worlds is None:
            served = ", ".join(f"{q.start} -> {q.goal}" for q in prior.trees)
            raise QueryError(
                f"this prior came from a tree file that holds training worlds only for its own query "
                f"({served}); to plan another query, rebuild it as a world prior with "
                "`drd build-tree --dataset DATASET.npz --out PRIOR.npz`"
            )
        if isinstance(start, int) and isinstance(goal, int):
            query = prior_query(prior, start, goal, self.columns)
        else:
            if self.connector is None:
                raise QueryError("this planner has no connector: states off the graph are refused")
            query = connected_query(prior, start, goal, self.connector, self.sample_index(), self.columns)
        probe = self._probe(query)
        if probe is not None or self.library_waits:  # the library waits until a plan needs it
            label = "connected" if query.connected else "online"
            theta, spent = self._theta(query), time.perf_counter() - t0
            return QueryModel(query, None, None, theta, label, spent, probe=probe, library_pending=True)
        return self._library_model(query, t0)

    def library_cost_ms(self, *, joined: bool = False) -> float:
        """What buying a new query's library costs in CPU milliseconds (the lead's price; measured once).

        :attr:`fixed_library_cost_ms` when set; else the median CPU time, over :data:`LIBRARY_COST_QUERIES` random
        queries that some training world joins (seeded by the prior's library seed), of building the library and
        tree and running the library stage (:attr:`price_stage`: the method's selections; the checks are table
        look-ups) to its end in one training world's outcomes, measured on this machine on first need
        (:meth:`warm_up`): between random vertices, or (``joined``) between random states in the box of the
        vertex states, joined to the graph by the connector (the joins are not timed: any planner makes them).
        The searches they leave for their goals are dropped.
        """
        if self.fixed_library_cost_ms is not None:
            return self.fixed_library_cost_ms
        return self._measured(joined)[0]

    def lead_check_ms(self, *, joined: bool = False) -> float:
        """The lead's own CPU per check in milliseconds (its searches and bookkeeping, the check itself not counted).

        :attr:`fixed_lead_check_ms` while the price is fixed; else measured with :meth:`library_cost_ms` on
        the same random queries: the lead run on each against one training world's outcomes (at most
        :data:`LEAD_COST_CHECKS` checks), its CPU time over all its checks.
        """
        if self.fixed_library_cost_ms is not None:
            return self.fixed_lead_check_ms
        return self._measured(joined)[1]

    def _measured(self, joined: bool) -> tuple[float, float]:
        joined = joined and self.connector is not None and self.prior.graph.vertex_states is not None
        if joined not in self._library_cost_ms:
            self._library_cost_ms[joined] = self._measure_library_cost(joined)
        return self._library_cost_ms[joined]

    def _measure_library_cost(self, joined: bool) -> tuple[float, float]:
        """(median library CPU ms, the lead's CPU ms per check) on random queries of one kind."""
        prior = self.prior
        graph = prior.graph
        if prior.worlds is None or graph.num_vertices < 2:
            return 0.0, 0.0
        rng = np.random.default_rng(prior.library_seed)
        kept = set(self.search.goals_kept)
        spent: list[float] = []
        lead_s, lead_count = 0.0, 0
        for _ in range(LIBRARY_COST_QUERIES * 20):
            if len(spent) == LIBRARY_COST_QUERIES:
                break
            try:
                query = self._random_query(rng, joined)
            except QueryError:
                continue
            oracle = _training_oracle(query, int(rng.integers(prior.worlds.shape[0])))
            t0 = time.process_time()
            model = self._library_model(query, time.perf_counter())
            if model.library is not None:  # a query no training world joins costs little and says nothing
                if self.price_stage is not None:
                    self.price_stage(model, oracle)
                spent.append(time.process_time() - t0)
                seconds, checks = _lead_time(prior, query, oracle)
                lead_s, lead_count = lead_s + seconds, lead_count + checks
            if query.goal < graph.num_vertices and query.goal not in kept:
                self.search.drop_tree(query.goal)
        library_ms = 1e3 * float(np.median(spent)) if spent else 0.0
        return library_ms, 1e3 * lead_s / lead_count if lead_count else 0.0

    def _random_query(self, rng: np.random.Generator, joined: bool) -> QueryGraph:
        """A random query between two vertices, or (``joined``) two states joined to the graph."""
        prior = self.prior
        graph = prior.graph
        if not joined:
            start, goal = (int(v) for v in rng.choice(graph.num_vertices, size=2, replace=False))
            return prior_query(prior, start, goal, self.columns)
        states = graph.vertex_states
        assert states is not None and self.connector is not None
        low, high = states.min(axis=0), states.max(axis=0)
        ends = [rng.uniform(low, high) for _ in range(2)]
        return connected_query(prior, ends[0], ends[1], self.connector, self.sample_index(), self.columns)

    def with_library(self, model: QueryModel) -> QueryModel:
        """A query's model with its pending library and tree built (in its place in the cache); others as they are."""
        if not model.library_pending:
            return model
        built = self._library_model(model.query, time.perf_counter(), model.theta)
        for key, cached in self._cache.items():
            if cached.query is model.query:
                self._cache[key] = built
                break
        return built

    def _probe(self, query: QueryGraph) -> Probe | None:
        """The union path of a query without a precomputed tree, if likely enough free."""
        prior = self.prior
        if self.probe_probability is None or prior.worlds is None:
            return None
        return union_probe(self.search, query, prior.world_weights, probability=self.probe_probability)

    def _library_model(self, query: QueryGraph, t0: float, theta: FloatArray | None = None) -> QueryModel:
        """The query's model with its library (and tree) built now; ``t0``: when its build began.

        ``theta``: BiSECt's training bias when already computed for the query (a pending model's), else None.
        """
        prior = self.prior
        library = query_library(
            self.search,
            query.graph.edges,
            query.start if query.start_joins is None else query.start_joins,
            query.goal if query.goal_joins is None else query.goal_joins,
            start_vertex=query.start,
            max_paths=prior.max_paths,
        )
        tree = None if library is None else self._tree(query, library)
        label = "connected" if query.connected else "online"
        bias = self._theta(query) if theta is None else theta
        return QueryModel(query, library, tree, bias, label, time.perf_counter() - t0)

    def _theta(self, query: QueryGraph) -> FloatArray:
        """(E',) BiSECt's training bias over the query's edges."""
        prior, worlds = self.prior, query.worlds
        assert worlds is not None
        if not query.connected:
            return prior.edge_marginal
        if prior.world_weights is not None:  # weighted worlds: the whole matrix once
            return bias_from_worlds(worlds.dense, prior.world_weights, alpha=prior.alpha)
        theta: FloatArray = prior.alpha * worlds.free_fraction + (1.0 - prior.alpha) * 0.5
        return theta

    def _tree(self, query: QueryGraph, library: object) -> TreeNodes:
        """BiSECt from the root when the online switch threshold is 1, else DiRECt grown online."""
        from drd_planner.core.library import PathLibrary

        assert isinstance(library, PathLibrary) and query.worlds is not None
        prior = self.prior
        if prior.eta >= 1.0:
            outcomes = query.worlds.columns(library.library_edges)
            return RootTree(outcomes, library, weights=prior.world_weights, region_rule=prior.region_rule)
        return LazyDirectTree(
            query.worlds.dense,
            library,
            query.edge_costs,
            weights=prior.world_weights,
            expand_threshold=self._expand,
            region_rule=prior.region_rule,
        )


def _cache_key(endpoint: int | FloatArray) -> object:
    """A hashable key of a vertex id or a state (its exact float64 bytes)."""
    return endpoint if isinstance(endpoint, int) else np.asarray(endpoint, dtype=np.float64).tobytes()


def _training_oracle(query: QueryGraph, world: int) -> TableOracle:
    """The outcomes of training world ``world`` over the query's edges (its joins' imputed)."""
    worlds = query.worlds
    assert worlds is not None
    return TableOracle(np.concatenate([worlds.base[world], worlds.extra[world]]))


def _lead_time(prior: WorldPrior, query: QueryGraph, oracle: TableOracle) -> tuple[float, int]:
    """(CPU seconds, checks) of the lead on ``query`` against ``oracle`` (a table: the lead's own time)."""
    t0 = time.process_time()
    episode = lazy_search(prior, query, oracle, {}, budget=LEAD_COST_CHECKS, deadline=None, stage="lead")
    return time.process_time() - t0, len(episode.checks)
