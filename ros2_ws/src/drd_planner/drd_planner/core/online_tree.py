"""DiRECt grown online: the decision tree of a query, built lazily along the branches actually taken.

The offline tree (:func:`drd_planner.core.tree.build_tree`) expands every node breadth-first before
any episode. For a query met for the first time that would cost seconds, yet an episode only walks
one branch. :class:`LazyDirectTree` computes a node's DiRECt edge the first time an episode stands on
it, with exactly the offline rules: the root is always expanded; another node only while its
consistent prior mass is at least ``expand_threshold`` of the training mass; its edge is
:func:`~drd_planner.core.tree.direct_node_edge` over its consistent worlds; both children are made
when it is expanded. So an episode on a lazy tree makes the same checks as on the offline tree built
from the same worlds, library and options (tested), and the nodes it grew stay for the next episode
of the same query (the planner caches the tree per query).
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.direct import DirectSelector
from drd_planner.core.library import PathLibrary
from drd_planner.core.posterior import TrainingOutcomes
from drd_planner.core.region_rule import DEFAULT_REGION_RULE, NodeRegionInputs, check_region_rule
from drd_planner.core.tree import (
    DEFAULT_EXPAND_THRESHOLD,
    NO_CHILD,
    NO_EDGE,
    direct_node_edge,
    leaf_bias,
    node_summary,
)
from drd_planner.exceptions import ProblemError

#: Nodes one lazy tree may hold; past it, nodes become leaves (BiSECt takes over), so memory stays bounded.
DEFAULT_MAX_NODES = 4096


class LazyDirectTree:
    """A DiRECt tree over the training worlds ``X`` for one path library, grown on demand.

    Implements :class:`drd_planner.core.tree.TreeNodes`.

    Args:
        X: (n, E) bool training worlds' edge outcomes (True = free).
        library: the m paths of the query.
        edge_costs: (E,) positive check costs.
        weights: (n,) positive prior weights, or None for uniform.
        expand_threshold: a non-root node is expanded only if its fraction is at least this.
        max_prob_region: restrict a node's tests to the best-supported path's edges (as offline).
        max_nodes: cap on the nodes held; a node that would exceed it becomes a leaf.
        region_rule: which path ``max_prob_region`` restricts to (as offline; the paper's by default).
    """

    def __init__(
        self,
        X: npt.ArrayLike,
        library: PathLibrary,
        edge_costs: npt.ArrayLike,
        *,
        weights: npt.ArrayLike | None = None,
        expand_threshold: float = DEFAULT_EXPAND_THRESHOLD,
        max_prob_region: bool = True,
        max_nodes: int = DEFAULT_MAX_NODES,
        region_rule: str = DEFAULT_REGION_RULE,
    ) -> None:
        x = np.asarray(X, dtype=bool)
        if x.ndim != 2 or x.shape[1] != library.num_edges or x.shape[0] == 0:
            raise ProblemError(
                f"a lazy DiRECt tree needs (n >= 1, {library.num_edges}) training outcomes, got {x.shape}"
            )
        self._X = x
        self._library = library
        self._costs = np.asarray(edge_costs, dtype=np.float64)
        self._prior = None if weights is None else np.asarray(weights, dtype=np.float64)
        self._weights = np.ones(x.shape[0]) if self._prior is None else self._prior
        self._total = float(self._weights.sum())
        self._expand = float(expand_threshold)
        self._max_prob_region = max_prob_region
        self._max_nodes = int(max_nodes)
        self._region = (
            None
            if check_region_rule(region_rule) == DEFAULT_REGION_RULE
            else NodeRegionInputs(region_rule, x, library, self._costs)
        )
        self._lib_edges = library.library_edges
        self._r_float: FloatArray | None = None
        self._selector: DirectSelector | None = None
        # Per node: consistent worlds, fraction, edge (None = not yet decided), children.
        self._active: list[IntArray] = [np.arange(x.shape[0], dtype=np.int64)]
        self._fraction: list[float] = [1.0 if self._total > 0 else 0.0]
        self._edge: list[int | None] = [None]
        self._children: list[list[int]] = [[NO_CHILD, NO_CHILD]]
        self._parent: list[int] = [-1]

    @property
    def num_edges(self) -> int:
        """E."""
        return self._library.num_edges

    @property
    def num_paths(self) -> int:
        """M."""
        return self._library.num_paths

    @property
    def region_rule(self) -> str:
        """The region rule of the nodes (:class:`~drd_planner.core.tree.TreeNodes`)."""
        return DEFAULT_REGION_RULE if self._region is None else self._region.rule

    @property
    def num_nodes(self) -> int:
        """Nodes grown so far."""
        return len(self._edge)

    @property
    def num_worlds(self) -> int:
        """n, the training worlds."""
        return int(self._X.shape[0])

    @cached_property
    def training_outcomes(self) -> TrainingOutcomes:
        """The training worlds' library-edge outcomes for the posterior leaf (built once)."""
        return TrainingOutcomes(
            np.ascontiguousarray(self._X[:, self._lib_edges]),
            self._lib_edges,
            self.num_edges,
            weights=self._prior,
        )

    def node_fraction(self, node: int) -> float:
        """The node's consistent prior mass over the training mass."""
        return self._fraction[node]

    def node_edge(self, node: int) -> int:
        """The node's DiRECt edge (computed now if this is the first visit), or NO_EDGE at a leaf."""
        edge = self._edge[node]
        if edge is None:
            edge = self._expand_node(node)
        return edge

    def node_child(self, node: int, free: bool) -> int:
        """The child for the outcome (NO_CHILD before the node is expanded or at a leaf)."""
        return self._children[node][int(free)]

    def bias(self, node: int, *, alpha: float = 0.99) -> FloatArray:
        """(E,) BiSECt's bias from the node's consistent worlds, as the offline tree stores it."""
        active = self._active[node]
        if active.size == 0:
            free = np.full(self._lib_edges.size, 0.5, dtype=np.float32)
        else:
            free, _ = node_summary(
                self._weights[active],
                self._X[np.ix_(active, self._lib_edges)].astype(np.float64),
                self._r()[active],
            )
        return leaf_bias(self.num_edges, self._lib_edges, free, alpha=alpha)

    def _r(self) -> FloatArray:
        if self._r_float is None:
            self._r_float = np.asarray(self._library.valid_paths(self._X), dtype=np.float64)
        return self._r_float

    def _expand_node(self, node: int) -> int:
        active = self._active[node]
        edge: int | None = None
        may_expand = node == 0 or (self._total > 0 and self._fraction[node] >= self._expand)
        if may_expand and active.size and len(self._edge) + 2 <= self._max_nodes:
            if self._selector is None:
                self._selector = DirectSelector(self._X, self._r() > 0, self._costs, prior=self._prior)
            edge = direct_node_edge(
                self._selector,
                active,
                self._weights,
                self._r(),
                self._library,
                max_prob_region=self._max_prob_region,
                region=self._region,
                checked=self._checked_mask(node) if self._region is not None else None,
            )
        if edge is None:
            self._edge[node] = NO_EDGE
            return NO_EDGE
        self._edge[node] = edge
        outcome = self._X[active, edge]
        for x in (0, 1):
            child_active = active[outcome == bool(x)]
            self._active.append(child_active)
            self._fraction.append(float(self._weights[child_active].sum()) / self._total)
            self._edge.append(None)
            self._children.append([NO_CHILD, NO_CHILD])
            self._parent.append(node)
            self._children[node][x] = len(self._edge) - 1
        return edge

    def _checked_mask(self, node: int) -> BoolArray:
        """(E,) the edges checked on the way from the root to ``node``."""
        mask = np.zeros(self.num_edges, dtype=bool)
        while self._parent[node] >= 0:
            node = self._parent[node]
            mask[self._edge[node]] = True
        return mask
