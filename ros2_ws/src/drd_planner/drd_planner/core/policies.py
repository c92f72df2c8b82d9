"""Policies on the episode runner, all registered in :data:`POLICIES`.

BiSECt alone, the DiRECt tree then BiSECt, the tree alone, and the baselines
(:mod:`drd_planner.core.baselines`, :mod:`drd_planner.core.lazysp`). Every policy is pure and
seeded: the same inputs and seed give the same checks.

The planner's own policies are the ones this module defines (:data:`CORE_POLICIES`). Other packages
add theirs with :func:`register_policy` when they are imported: the benchmark package registers the
learned LazySP selectors (:mod:`drd_planner.bench.learned_policies`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray
from drd_planner.core.baselines import LazySPSet, MaxTally, MVoI, RandomEdge, SetCover, WeightedMaxTally
from drd_planner.core.bisect import Bisect
from drd_planner.core.episode import Policy
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.lazysp import SELECTORS, LazySP, LazySPSettings, lazysp_name
from drd_planner.core.library import PathLibrary
from drd_planner.core.posterior import ConsistentWorldsBias
from drd_planner.core.region_rule import DEFAULT_REGION_RULE, check_region_rule
from drd_planner.core.tree import NO_CHILD, NO_EDGE, DecisionTree, TreeNodes
from drd_planner.exceptions import PolicyError, ProblemError

#: Default switch threshold: hand over to BiSECt when the consistent fraction is <= eta.
DEFAULT_ETA = 0.2
#: Default weight of the data term in the leaf bias.
DEFAULT_ALPHA = 0.99
#: kappa of ``bisect_posterior`` when the context gives none.
DEFAULT_PSEUDO_COUNT = 20.0


class BisectPolicy:
    """BiSECt with a fixed bias (``bisect`` with MaxProbReg, ``bisect_all`` without)."""

    def __init__(
        self,
        library: PathLibrary,
        theta: npt.ArrayLike,
        edge_costs: npt.ArrayLike,
        *,
        max_prob_region: bool = True,
        name: str | None = None,
        region_rule: str = DEFAULT_REGION_RULE,
    ) -> None:
        self._name = name or ("bisect" if max_prob_region else "bisect_all")
        self._bisect = Bisect(library, theta, edge_costs, max_prob_region=max_prob_region, region_rule=region_rule)

    @property
    def name(self) -> str:
        """Registry name."""
        return self._name

    @property
    def stage(self) -> str:
        """Always ``bisect``."""
        return "bisect"

    def select(self) -> int | None:
        """BiSECt's next edge."""
        return self._bisect.select()

    def observe(self, edge: int, free: bool) -> None:
        """Clamp the outcome."""
        self._bisect.observe(edge, free)


class TreeWalker:
    """Follows a decision tree (offline or grown online) one outcome at a time."""

    def __init__(self, tree: TreeNodes) -> None:
        self._tree = tree
        self._node = 0

    @property
    def node(self) -> int:
        """The current node."""
        return self._node

    def edge(self) -> int | None:
        """The edge the current node asks for, or None at a leaf."""
        e = self._tree.node_edge(self._node)
        return None if e == NO_EDGE else e

    def advance(self, free: bool) -> bool:
        """Move to the child for ``free``; False (and stay) when that child does not exist."""
        child = self._tree.node_child(self._node, free)
        if child == NO_CHILD:
            return False
        self._node = child
        return True


class DirectBisectPolicy:
    """The paper's method: walk the DiRECt tree, then BiSECt (MaxProbReg) with the node's bias.

    The switch happens when the tree has no child for the outcome, the node has no edge, or the
    node's consistent fraction is at or below ``eta``. With ``pseudo_count`` (kappa) set, BiSECt's
    bias keeps being re-conditioned on every later outcome (the authors' ``update_posterior``
    option, :class:`~drd_planner.core.posterior.ConsistentWorldsBias`); None keeps it fixed after
    the switch as in the paper's benchmark. The posterior needs a tree that carries its training
    worlds (``DecisionTree.world_free``). ``region_rule`` picks BiSECt's path after the switch
    (:mod:`~drd_planner.core.region_rule`; None: the rule the tree was built with, so one option of
    ``build_tree`` sets both stages).
    """

    def __init__(
        self,
        tree: TreeNodes,
        library: PathLibrary,
        edge_costs: npt.ArrayLike,
        *,
        eta: float = DEFAULT_ETA,
        alpha: float = DEFAULT_ALPHA,
        pseudo_count: float | None = None,
        name: str = "direct_bisect",
        region_rule: str | None = None,
    ) -> None:
        _check_tree_fits(tree, library)
        self._region_rule = check_region_rule(tree.region_rule if region_rule is None else region_rule)
        if pseudo_count is not None and tree.training_outcomes is None:
            raise ProblemError(
                "the posterior-updating leaf needs the training worlds in the tree "
                "(rebuild the tree; tree files of format version 1 do not carry them)"
            )
        self._pseudo_count = pseudo_count
        self._posterior: ConsistentWorldsBias | None = None
        self._tree = tree
        self._library = library
        self._costs = np.asarray(edge_costs, dtype=np.float64)
        self._eta = eta
        self._alpha = alpha
        self._name = name
        self._walker = TreeWalker(tree)
        self._observed: dict[int, bool] = {}
        self._bisect: Bisect | None = None
        self._posterior_aligned = False
        self._switch_node: int | None = None
        if self._should_switch(0):
            self._switch(0)

    @property
    def name(self) -> str:
        """Registry name."""
        return self._name

    @property
    def stage(self) -> str:
        """``tree`` while walking the tree, ``bisect`` after the switch."""
        return "tree" if self._bisect is None else "bisect"

    @property
    def switch_node(self) -> int | None:
        """The tree node at which BiSECt took over (None while still in the tree)."""
        return self._switch_node

    def _should_switch(self, node: int) -> bool:
        # The fraction first: a tree grown online then never computes an edge it will not use.
        return self._tree.node_fraction(node) <= self._eta or self._tree.node_edge(node) == NO_EDGE

    @property
    def pseudo_count(self) -> float | None:
        """Kappa of the posterior-updating leaf, or None (fixed bias after the switch)."""
        return self._pseudo_count

    def _switch(self, node: int) -> None:
        self._switch_node = node
        if self._pseudo_count is None:
            theta = self._tree.bias(node, alpha=self._alpha)
        else:
            outcomes = self._tree.training_outcomes
            assert outcomes is not None
            self._posterior = ConsistentWorldsBias(
                outcomes, pseudo_count=self._pseudo_count, alpha=self._alpha, observations=self._observed
            )
            theta = self._posterior.theta()
        self._bisect = Bisect(
            self._library, theta, self._costs, observations=self._observed, region_rule=self._region_rule
        )
        # The posterior's columns are usually the library's own edges: its bias then goes in as it is.
        self._posterior_aligned = self._posterior is not None and np.array_equal(
            self._posterior.library_edges, self._bisect.library_edges
        )

    def select(self) -> int | None:
        """Tree edge while in the tree; BiSECt's choice afterwards.

        A tree edge whose outcome is already known (heard before the tree asked, e.g. from the probe) is not
        asked again: the walk follows the known outcome to the child, switching to BiSECt where it would.
        """
        while self._bisect is None:
            edge = self._walker.edge()
            if edge is None:
                self._switch(self._walker.node)
            elif edge not in self._observed:
                return edge
            else:
                self._descend(self._observed[edge])
        bisect: Bisect = self._bisect
        return bisect.select()

    def observe(self, edge: int, free: bool) -> None:
        """Record the outcome, step down the tree, and switch to BiSECt when due."""
        self._observed[edge] = free
        if self._bisect is not None:
            self._bisect.observe(edge, free)
            if self._posterior is not None:  # the bias of the library edges, updated when worlds drop
                dropped = self._posterior.observe(edge, free)
                if self._posterior_aligned and not dropped:  # the same bias: log p_i summed again if due
                    self._bisect.set_library_theta(None)
                elif self._posterior_aligned:
                    self._bisect.set_library_theta(self._posterior.library_theta())
                else:
                    self._bisect.set_theta(self._posterior.library_theta(), edges=self._posterior.library_edges)
            return
        if edge == self._walker.edge():
            self._descend(free)
        # Another edge's outcome (checked before the tree asked for it): kept in ``_observed``, followed when
        # the tree asks for that edge, and given to BiSECt at the switch.

    def _descend(self, free: bool) -> None:
        """Step from the current node to its child for ``free``; switch to BiSECt when there is none or due."""
        node = self._walker.node
        if not self._walker.advance(free):
            self._switch(node)
        elif self._should_switch(self._walker.node):
            self._switch(self._walker.node)


class DirectOnlyPolicy:
    """DiRECt alone: walk the tree to its end, then check the best-supported path's remaining edges.

    The remaining edges are checked in a seeded random order. If that path turns out blocked, the
    policy gives up (the episode fails): this is the baseline whose failure rate the paper reports.
    """

    def __init__(
        self,
        tree: DecisionTree,
        library: PathLibrary,
        *,
        seed: int = 0,
        name: str = "direct_only",
    ) -> None:
        _check_tree_fits(tree, library)
        self._tree = tree
        self._library = library
        self._rng = np.random.default_rng(seed)
        self._name = name
        self._walker = TreeWalker(tree)
        self._observed: dict[int, bool] = {}
        self._queue: list[int] | None = None
        self._failed = False

    @property
    def name(self) -> str:
        """Registry name."""
        return self._name

    @property
    def stage(self) -> str:
        """``tree`` then ``path``."""
        return "tree" if self._queue is None else "path"

    def _start_final_path(self) -> None:
        path = int(self._tree.best_path[self._walker.node])
        if path < 0:
            self._queue = []
            self._failed = True
            return
        edges = self._library.path_edges[path]
        if any(self._observed.get(int(e)) is False for e in edges):
            self._queue = []
            self._failed = True
            return
        todo = [int(e) for e in edges if int(e) not in self._observed]
        self._queue = [todo[i] for i in self._rng.permutation(len(todo))]

    def select(self) -> int | None:
        """Tree edge, then the chosen path's unchecked edges; None once done or failed."""
        if self._queue is None:
            edge = self._walker.edge()
            if edge is not None and edge not in self._observed:
                return edge
            self._start_final_path()
        assert self._queue is not None
        if self._failed or not self._queue:
            return None
        return self._queue[0]

    def observe(self, edge: int, free: bool) -> None:
        """Step down the tree, or tick off the final path's edge."""
        self._observed[edge] = free
        if self._queue is None:
            if not self._walker.advance(free):
                self._start_final_path()
            return
        if self._queue and self._queue[0] == edge:
            self._queue.pop(0)
        if not free:
            self._failed = True


def _check_tree_fits(tree: TreeNodes, library: PathLibrary) -> None:
    if tree.num_edges != library.num_edges or tree.num_paths != library.num_paths:
        raise ProblemError(
            f"tree was built for {tree.num_edges} edges / {tree.num_paths} paths, but the problem has "
            f"{library.num_edges} / {library.num_paths}"
        )


@dataclass(frozen=True)
class PolicyContext:
    """What a policy factory may use: the library, costs, training bias, tree and a seed.

    ``eta`` and ``pseudo_count`` configure ``direct_bisect``'s switch and leaf (see
    :class:`DirectBisectPolicy`). ``graph``, ``start`` and ``goal`` are needed by the policies in
    :func:`graph_policies`. ``train_worlds`` ((n_train, E) bool, True = free, over every graph edge)
    and their ``train_weights`` ((n_train,) prior weights, None: uniform) are needed by the learned
    LazySP selectors (:mod:`drd_planner.bench.lazysp_learned`). ``imitation_model`` is the selector of
    ``lazysp_imitation`` (:class:`drd_planner.bench.lazysp_imitation.ImitationModel`, opaque to the core:
    its factory checks the type), trained once per dataset by the caller
    (``drd_planner.bench.runner.run_benchmark``), never per episode.
    """

    library: PathLibrary
    edge_costs: FloatArray
    train_theta: FloatArray
    tree: TreeNodes | None
    seed: int
    eta: float = DEFAULT_ETA
    alpha: float = DEFAULT_ALPHA
    pseudo_count: float | None = None
    graph: ExplicitGraph | None = None
    start: int | None = None
    goal: int | None = None
    train_worlds: BoolArray | None = None
    train_weights: FloatArray | None = None
    imitation_model: object | None = None


PolicyFactory = Callable[[PolicyContext], Policy]


def _need_tree(ctx: PolicyContext) -> TreeNodes:
    if ctx.tree is None:
        raise ProblemError("this policy needs a decision tree")
    return ctx.tree


def _need_offline_tree(ctx: PolicyContext) -> DecisionTree:
    if not isinstance(ctx.tree, DecisionTree):
        raise ProblemError("direct_only needs a decision tree built offline (drd build-tree)")
    return ctx.tree


def need_graph(ctx: PolicyContext) -> ExplicitGraph:
    """The context's graph, checked against the library (for factories of graph policies).

    Raises:
        ProblemError: no graph, or one whose edge count differs from the library's.
    """
    if ctx.graph is None:
        raise ProblemError("this policy needs the graph (PolicyContext.graph)")
    if ctx.graph.num_edges != ctx.library.num_edges:
        raise ProblemError(f"graph has {ctx.graph.num_edges} edges but the library indexes {ctx.library.num_edges}")
    return ctx.graph


def _lazysp(selector: str) -> PolicyFactory:
    def make(ctx: PolicyContext) -> Policy:
        graph = need_graph(ctx)
        if ctx.start is None or ctx.goal is None:
            raise ProblemError("lazysp needs the start and goal vertices (PolicyContext.start/goal)")
        return LazySP(graph, ctx.start, ctx.goal, LazySPSettings(selector=selector, seed=ctx.seed))

    return make


def _lazysp_set(weighted: bool) -> PolicyFactory:
    def make(ctx: PolicyContext) -> Policy:
        lengths = ctx.library.path_costs(need_graph(ctx).lengths)  # geometric length of each path
        return LazySPSet(ctx.library, ctx.train_theta, lengths, weighted=weighted, seed=ctx.seed)

    return make


_REGISTRY: dict[str, PolicyFactory] = {
    "direct_bisect": lambda c: DirectBisectPolicy(
        _need_tree(c), c.library, c.edge_costs, eta=c.eta, alpha=c.alpha, pseudo_count=c.pseudo_count
    ),
    "direct_bisect_fixed": lambda c: DirectBisectPolicy(
        _need_tree(c), c.library, c.edge_costs, eta=DEFAULT_ETA, alpha=c.alpha, name="direct_bisect_fixed"
    ),
    "direct_only": lambda c: DirectOnlyPolicy(_need_offline_tree(c), c.library, seed=c.seed),
    "bisect": lambda c: BisectPolicy(c.library, c.train_theta, c.edge_costs, max_prob_region=True),
    "bisect_posterior": lambda c: DirectBisectPolicy(
        _need_tree(c),
        c.library,
        c.edge_costs,
        eta=1.0,
        alpha=c.alpha,
        pseudo_count=DEFAULT_PSEUDO_COUNT if c.pseudo_count is None else c.pseudo_count,
        name="bisect_posterior",
    ),
    "bisect_all": lambda c: BisectPolicy(c.library, c.train_theta, c.edge_costs, max_prob_region=False),
    "max_tally": lambda c: MaxTally(c.library, c.train_theta, name="max_tally", seed=c.seed),
    "max_tally_all": lambda c: MaxTally(
        c.library, c.train_theta, name="max_tally_all", max_prob_region=False, seed=c.seed
    ),
    "weighted_max_tally": lambda c: WeightedMaxTally(
        c.library, c.train_theta, name="weighted_max_tally", max_prob_region=False, seed=c.seed
    ),
    "set_cover": lambda c: SetCover(c.library, c.train_theta, name="set_cover", seed=c.seed),
    "set_cover_all": lambda c: SetCover(
        c.library, c.train_theta, name="set_cover_all", max_prob_region=False, seed=c.seed
    ),
    "mvoi": lambda c: MVoI(c.library, c.train_theta, seed=c.seed),
    "random": lambda c: RandomEdge(c.library, c.train_theta, name="random", seed=c.seed),
    "random_all": lambda c: RandomEdge(c.library, c.train_theta, name="random_all", max_prob_region=False, seed=c.seed),
    "lazysp_set": _lazysp_set(weighted=True),
    "lazysp_set_random": _lazysp_set(weighted=False),
    **{lazysp_name(s): _lazysp(s) for s in SELECTORS},
}
#: The planner's own policies (those this module defines), in registry order.
CORE_POLICIES: tuple[str, ...] = tuple(_REGISTRY)
#: Every registered policy by name: :data:`CORE_POLICIES` and those added by :func:`register_policy`
#: (a read-only view that follows the registrations).
POLICIES: Mapping[str, PolicyFactory] = MappingProxyType(_REGISTRY)

#: Policies that need a decision tree. ``direct_bisect_fixed`` is the combined method exactly as in
#: the paper's benchmark (threshold ``DEFAULT_ETA``, fixed leaf bias) whatever the context says, so
#: that a run with validated settings (see ``core.switch_threshold``) can report both side by side.
#: ``bisect_posterior`` is BiSECt whose bias is re-conditioned on the training worlds from the first
#: check on (the tree's root with the posterior leaf): it needs the tree only for its training worlds,
#: and shows how much of ``direct_bisect``'s gain the posterior alone gives.
TREE_POLICIES = frozenset({"direct_bisect", "direct_bisect_fixed", "direct_only", "bisect_posterior"})
#: Tree policies that are the paper's method exactly, so a benchmark runs them on a tree built with the
#: paper's region rule even when the run's tree uses another (``drd_planner.bench.runner.paper_rule_tree``).
PAPER_RULE_POLICIES = frozenset({"direct_bisect_fixed"})

#: Policies that need ``PolicyContext.graph`` (the ``lazysp`` family also ``start`` and ``goal``),
#: followed by the graph policies added with ``register_policy(..., needs_graph=True)``.
_GRAPH_POLICIES: list[str] = [
    *(lazysp_name(s) for s in SELECTORS),
    "lazysp_set",
    "lazysp_set_random",
]


def graph_policies() -> tuple[str, ...]:
    """The registered policies that need ``PolicyContext.graph`` (the core's first, then the added ones)."""
    return tuple(_GRAPH_POLICIES)


def register_policy(name: str, factory: PolicyFactory, *, needs_graph: bool = False) -> None:
    """Add a policy to :data:`POLICIES` under ``name`` (how the benchmark package adds its research policies).

    Args:
        name: the registry name (``drd bench --policies``, ``run_world``); must not be registered yet.
        factory: builds the policy from a :class:`PolicyContext`.
        needs_graph: the policy needs ``PolicyContext.graph`` (listed by :func:`graph_policies`).

    Raises:
        PolicyError: ``name`` is already registered.
    """
    if name in _REGISTRY:
        raise PolicyError(f"policy {name!r} is already registered; registered: {', '.join(sorted(_REGISTRY))}")
    _REGISTRY[name] = factory
    if needs_graph:
        _GRAPH_POLICIES.append(name)
