"""The world prior: one graph, its sampled training worlds over every edge, and precomputed trees.

The world database does not depend on the query: X (worlds x edges) holds every edge's outcome in
every sampled training world; only a path library and its R depend on the start and goal. A
:class:`WorldPrior` therefore serves any (start, goal) of its graph (:class:`~drd_planner.planner.Planner`
builds the library online), and keeps zero or more offline DiRECt trees, each for one named query, as a
cache for the queries a robot asks often.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any, TypedDict

if TYPE_CHECKING:
    from typing_extensions import Unpack

import numpy as np

from drd_planner.arrays import BoolArray, FloatArray
from drd_planner.core.bisect import bias_from_worlds
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.library import PathLibrary
from drd_planner.core.policies import DEFAULT_ALPHA, DEFAULT_ETA
from drd_planner.core.problem import Problem
from drd_planner.core.region_rule import DEFAULT_REGION_RULE, check_region_rule
from drd_planner.core.tree import DecisionTree
from drd_planner.exceptions import ProblemError

#: Library size of an online query library (the authors' m).
DEFAULT_MAX_PATHS = 500


@dataclass(frozen=True)
class LeafSetting:
    """When a tree hands over to BiSECt, and how BiSECt's bias is re-conditioned after that.

    Attributes:
        eta: switch threshold in (0, 1]: the tree is left once the consistent fraction is at or below it.
        pseudo_count: kappa (worlds) of the posterior leaf, or None for the paper's fixed leaf bias.
    """

    eta: float
    pseudo_count: float | None

    def __post_init__(self) -> None:
        if not 0.0 < self.eta <= 1.0:
            raise ProblemError(f"eta must lie in (0, 1]; got {self.eta}")
        if self.pseudo_count is not None and not (np.isfinite(self.pseudo_count) and self.pseudo_count > 0):
            raise ProblemError(f"pseudo_count must be a positive number of worlds, got {self.pseudo_count}")


@dataclass(frozen=True)
class QueryTree:
    """An offline DiRECt tree for one (start, goal) query, with the path library it was built on.

    Attributes:
        name: a label (the dataset name, or ``START-GOAL``).
        start: start vertex id.
        goal: goal vertex id.
        library: the tree's m paths (edge ids, and vertex sequences when known).
        tree: the decision tree.
        leaf: eta and kappa validated on this query (``drd build-tree`` validates them on held-out
            training worlds of the query itself), or None to use the prior's, which are validated on
            random queries. A query the robot asks often is worth a setting of its own: on the
            Terrain dataset's own query the tree pays at eta 0.4 (8.1 checks against 10.2 for BiSECt)
            while random queries, mostly short, choose eta 1.
    """

    name: str
    start: int
    goal: int
    library: PathLibrary
    tree: DecisionTree
    leaf: LeafSetting | None = None


@dataclass(frozen=True)
class WorldPrior:
    """What the planner loads to plan any query in one graph.

    Attributes:
        name: a label (dataset name).
        domain: the domain registry name (``helicopter``, ``arm``, ``planar``, ``gccd``, ...).
        graph: the explicit graph (vertex states, edges, lengths).
        edge_costs: (E,) float64 positive cost of checking each edge.
        worlds: (n, E) bool training worlds' outcomes over every edge (True = free), or None for a
            prior read from a tree file of format version 1 or 2, which holds only its own query's
            library edges (it then serves that query only).
        world_weights: (n,) float64 positive prior weights of the worlds, or None for uniform.
        trees: the precomputed trees, at most one per (start, goal).
        eta: switch threshold to BiSECt (validated for the dataset's own query when built).
        alpha: weight of the data term in BiSECt's bias.
        pseudo_count: kappa of the posterior leaf, or None for the paper's fixed leaf bias.
        region_rule: the region rule of the trees built online for new queries
            (:mod:`~drd_planner.core.region_rule`); precomputed trees keep the one they were built with.
        max_paths: m of the libraries built online.
        library_seed: seed of the online libraries' world order.
        domain_spec: JSON-safe spec that rebuilds the domain (and its FCL checker).
        check_metadata: how edges were checked (resolution, margin, ... with units).
        edge_trajectories: per edge a (K_e, D) float64 array of states along it, or None.
        provenance: JSON-safe build information; ``world_model`` names the world model of the training
            worlds when the problem named it (:func:`prior_from_problem`).
    """

    name: str
    domain: str
    graph: ExplicitGraph
    edge_costs: FloatArray
    worlds: BoolArray | None
    world_weights: FloatArray | None = None
    trees: tuple[QueryTree, ...] = ()
    eta: float = DEFAULT_ETA
    alpha: float = DEFAULT_ALPHA
    pseudo_count: float | None = None
    region_rule: str = DEFAULT_REGION_RULE
    max_paths: int = DEFAULT_MAX_PATHS
    library_seed: int = 0
    domain_spec: dict[str, Any] = field(default_factory=dict)
    check_metadata: dict[str, Any] = field(default_factory=dict)
    edge_trajectories: tuple[FloatArray, ...] | None = None
    provenance: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        num_edges = self.graph.num_edges
        costs = np.asarray(self.edge_costs, dtype=np.float64)
        if costs.shape != (num_edges,) or not np.all(np.isfinite(costs)) or np.any(costs <= 0):
            raise ProblemError(f"edge costs must be ({num_edges},) finite and positive")
        object.__setattr__(self, "edge_costs", costs)
        if self.worlds is not None:
            self._check_worlds(num_edges)
        elif not self.trees:
            raise ProblemError("a prior without training worlds over every edge needs a precomputed tree")
        self._check_settings()
        self._check_trees(num_edges)

    def _check_worlds(self, num_edges: int) -> None:
        """Validate (and convert) the (n, E) training worlds and their (n,) weights."""
        x = np.asarray(self.worlds, dtype=bool)
        if x.ndim != 2 or x.shape[1] != num_edges or x.shape[0] == 0:
            raise ProblemError(f"prior worlds must be (n >= 1, {num_edges}) booleans, got {x.shape}")
        object.__setattr__(self, "worlds", x)
        if self.world_weights is not None:
            w = np.asarray(self.world_weights, dtype=np.float64)
            if w.shape != (x.shape[0],) or not np.all(np.isfinite(w)) or np.any(w <= 0):
                raise ProblemError(f"world weights must be ({x.shape[0]},) finite and positive")
            object.__setattr__(self, "world_weights", w)

    def _check_settings(self) -> None:
        """Validate eta, alpha, the pseudo-count, the region rule and the library size."""
        check_region_rule(self.region_rule)
        if not 0.0 < self.eta <= 1.0 or not 0.0 < self.alpha <= 1.0:
            raise ProblemError(f"eta and alpha must lie in (0, 1]; got {self.eta} and {self.alpha}")
        if self.pseudo_count is not None and not (np.isfinite(self.pseudo_count) and self.pseudo_count > 0):
            raise ProblemError(f"pseudo_count must be a positive number of worlds, got {self.pseudo_count}")
        if self.max_paths < 1:
            raise ProblemError(f"max_paths must be at least 1, got {self.max_paths}")

    def _check_trees(self, num_edges: int) -> None:
        """Validate the precomputed trees: one per query, endpoints in the graph, built for this graph."""
        seen: set[tuple[int, int]] = set()
        for qt in self.trees:
            key = (qt.start, qt.goal)
            if key in seen:
                raise ProblemError(f"two precomputed trees for the query {qt.start} -> {qt.goal}")
            seen.add(key)
            for label, v in (("start", qt.start), ("goal", qt.goal)):
                if not 0 <= v < self.graph.num_vertices:
                    raise ProblemError(f"tree {qt.name!r}: {label} vertex {v} outside the graph")
            if qt.library.num_edges != num_edges or qt.tree.num_edges != num_edges:
                raise ProblemError(f"tree {qt.name!r} was built for another graph ({qt.tree.num_edges} edges)")
            if qt.tree.num_paths != qt.library.num_paths:
                raise ProblemError(f"tree {qt.name!r} does not fit its library")

    @property
    def num_worlds(self) -> int:
        """n, the training worlds (0 when the prior has none over every edge)."""
        return 0 if self.worlds is None else int(self.worlds.shape[0])

    @property
    def serves_any_query(self) -> bool:
        """True when the prior has training worlds over every edge."""
        return self.worlds is not None

    @cached_property
    def edge_marginal(self) -> FloatArray:
        """(E,) theta_e = alpha * (weighted) free fraction of e over the training worlds + (1 - alpha) / 2."""
        if self.worlds is None:
            return np.full(self.graph.num_edges, 0.5)
        return bias_from_worlds(self.worlds, self.world_weights, alpha=self.alpha)

    def leaf_for(self, qt: QueryTree | None) -> LeafSetting:
        """The eta and kappa a query uses: its tree's own setting, else the prior's."""
        if qt is not None and qt.leaf is not None:
            return qt.leaf
        return LeafSetting(self.eta, self.pseudo_count)

    def tree_for(self, start: int, goal: int) -> QueryTree | None:
        """The precomputed tree of the query (start, goal), if any."""
        for qt in self.trees:
            if qt.start == start and qt.goal == goal:
                return qt
        return None

    def query_problem(self, qt: QueryTree) -> Problem:
        """A precomputed query as a :class:`Problem` (graph, library, costs, start, goal; no worlds)."""
        return Problem(
            name=qt.name,
            library=qt.library,
            edge_costs=self.edge_costs,
            graph=self.graph,
            start=qt.start,
            goal=qt.goal,
            metadata={
                "domain": self.domain,
                "domain_spec": self.domain_spec,
                "check_metadata": self.check_metadata,
            },
        )


class PriorOptions(TypedDict, total=False):
    """Optional settings of :func:`prior_from_problem` (the :class:`WorldPrior` fields of the same names)."""

    eta: float
    alpha: float
    pseudo_count: float | None
    region_rule: str
    max_paths: int
    library_seed: int
    edge_trajectories: tuple[FloatArray, ...] | None
    provenance: dict[str, Any] | None


def prior_from_problem(
    problem: Problem,
    *,
    domain: str,
    trees: tuple[QueryTree, ...] = (),
    **options: Unpack[PriorOptions],
) -> WorldPrior:
    """The prior of a problem's training worlds (its test worlds stay out: they are for benchmarks)."""
    worlds = problem.require_worlds()
    if problem.graph is None:
        raise ProblemError(f"problem {problem.name!r} has no graph; a world prior needs one")
    train = worlds.train_ids
    if train.size == 0:
        raise ProblemError(f"problem {problem.name!r} has no training worlds")
    weights = None if worlds.prior is None else worlds.prior[train]
    meta = problem.metadata
    return WorldPrior(
        name=problem.name,
        domain=domain,
        graph=problem.graph,
        edge_costs=problem.edge_costs,
        worlds=worlds.X[train],
        world_weights=weights,
        trees=trees,
        eta=options.get("eta", DEFAULT_ETA),
        alpha=options.get("alpha", DEFAULT_ALPHA),
        pseudo_count=options.get("pseudo_count"),
        region_rule=options.get("region_rule", DEFAULT_REGION_RULE),
        max_paths=options.get("max_paths", DEFAULT_MAX_PATHS),
        library_seed=options.get("library_seed", 0),
        domain_spec=dict(meta.get("domain_spec") or {}),
        check_metadata=dict(meta.get("check_metadata") or {}),
        edge_trajectories=options.get("edge_trajectories"),
        provenance=_provenance(meta, options.get("provenance")),
    )


def _provenance(meta: dict[str, Any], given: dict[str, Any] | None) -> dict[str, Any]:
    """The prior's provenance: ``given``, plus the world model of the training worlds when the problem names it.

    The world model tells whose terrain a map must be (a ``corridors`` prior's is one real site).
    """
    out = dict(given or {})
    model = meta.get("world_model")
    if isinstance(model, str) and model and "world_model" not in out:
        out["world_model"] = model
    return out
