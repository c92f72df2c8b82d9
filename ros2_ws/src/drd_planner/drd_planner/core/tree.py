"""The offline DiRECt decision tree (docs/algorithms.md, "The decision tree and the switch to BiSECt").

Built breadth-first from the root (all training worlds active). Each expanded node stores the
DiRECt edge to check; both children are created, and a child is expanded further only while its
consistent-world fraction is at least ``expand_threshold`` (:data:`DEFAULT_EXPAND_THRESHOLD`). For every node the tree
keeps what the online side needs without the database: the consistent-world count and fraction, the
fraction of consistent worlds in which each library edge is free (BiSECt's leaf bias), and the
library path with the most consistent worlds (DiRECt-only's final guess).
"""

from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt
from tqdm import tqdm

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.direct import DirectSelector
from drd_planner.core.library import PathLibrary
from drd_planner.core.posterior import TrainingOutcomes
from drd_planner.core.problem import Problem
from drd_planner.core.region_rule import DEFAULT_REGION_RULE, NodeRegionInputs, check_region_rule
from drd_planner.exceptions import ProblemError

NO_EDGE = -1
#: Default expansion threshold: nodes with at least this fraction of the training worlds are expanded.
#: 0.01 rather than 0.05: with eta validated among 0.01 and 0.02 too, the deeper trees need 0.816 of the
#: paper's method's checks on the 13 authors' sets against 0.847 (geometric mean; README, issue 18).
DEFAULT_EXPAND_THRESHOLD = 0.01
NO_CHILD = -1


@dataclass(frozen=True)
class DecisionTree:
    """A DiRECt decision tree over N nodes (node 0 is the root).

    Attributes:
        edge: (N,) int32 edge to check at the node, NO_EDGE (-1) at leaves.
        children: (N, 2) int32 child for outcome blocked (0) and free (1), NO_CHILD when absent.
        num_active: (N,) int32 training worlds consistent with the node.
        active_fraction: (N,) float64 prior mass of those worlds over the whole training mass.
        library_edges: (K,) int64 the library's edge ids (columns of ``free_fraction``).
        free_fraction: (N, K) float32 (weighted) fraction of the node's worlds in which each library
            edge is free; 0.5 where the node has no worlds.
        best_path: (N,) int32 library path valid in the most consistent worlds, -1 if none is.
        num_edges: E of the graph the tree was built for.
        num_paths: m of the library it was built for.
        info: build provenance (threshold, times, counts), JSON-safe.
        world_free: (n, K) bool outcome of each library edge in each training world, or None (tree
            files of format version 1). Needed only by the posterior-updating leaf
            (:mod:`drd_planner.core.posterior`).
        world_weights: (n,) float64 prior weights of those worlds, or None for uniform.
    """

    edge: npt.NDArray[np.int32]
    children: npt.NDArray[np.int32]
    num_active: npt.NDArray[np.int32]
    active_fraction: FloatArray
    library_edges: IntArray
    free_fraction: npt.NDArray[np.float32]
    best_path: npt.NDArray[np.int32]
    num_edges: int
    num_paths: int
    info: dict[str, Any] = field(default_factory=dict)
    world_free: npt.NDArray[np.bool_] | None = None
    world_weights: FloatArray | None = None

    @cached_property
    def training_outcomes(self) -> TrainingOutcomes | None:
        """The training worlds prepared for the posterior leaf (computed once), or None without them."""
        if self.world_free is None:
            return None
        return TrainingOutcomes(self.world_free, self.library_edges, self.num_edges, weights=self.world_weights)

    @property
    def num_nodes(self) -> int:
        """N."""
        return int(self.edge.shape[0])

    @property
    def region_rule(self) -> str:
        """The region rule the tree was built with (``info``; the paper's for files without it)."""
        return str(self.info.get("region_rule", DEFAULT_REGION_RULE))

    def depth(self) -> int:
        """Length of the longest root-to-leaf path, in checks."""
        depth = np.zeros(self.num_nodes, dtype=np.int64)
        for node in range(self.num_nodes):
            for child in self.children[node]:
                if child != NO_CHILD:
                    depth[child] = depth[node] + 1
        return int(depth.max())

    def bias(self, node: int, *, alpha: float = 0.99) -> FloatArray:
        """(E,) BiSECt bias at ``node``: alpha * free fraction + (1 - alpha) / 2 on library edges.

        Edges outside the library never matter to BiSECt and get 0.5.
        """
        return leaf_bias(self.num_edges, self.library_edges, self.free_fraction[node], alpha=alpha)

    def node_edge(self, node: int) -> int:
        """The edge ``node`` asks for, NO_EDGE at a leaf (:class:`TreeNodes`)."""
        return int(self.edge[node])

    def node_child(self, node: int, free: bool) -> int:
        """The child of ``node`` for the outcome ``free``, NO_CHILD when absent (:class:`TreeNodes`)."""
        return int(self.children[node, int(free)])

    def node_fraction(self, node: int) -> float:
        """Prior mass of the node's consistent worlds over the whole training mass (:class:`TreeNodes`)."""
        return float(self.active_fraction[node])


class TreeNodes(Protocol):
    """What a policy walking a DiRECt tree reads.

    The offline :class:`DecisionTree`, or the tree grown online along the branch taken
    (:class:`drd_planner.core.online_tree.LazyDirectTree`). Node 0 is the root; node ids are stable once handed out.
    """

    @property
    def num_edges(self) -> int:
        """E of the graph."""
        ...

    @property
    def num_paths(self) -> int:
        """M of the library."""
        ...

    @property
    def training_outcomes(self) -> TrainingOutcomes | None:
        """The training worlds for the posterior leaf, or None when the tree does not carry them."""
        ...

    @property
    def region_rule(self) -> str:
        """The region rule the tree's nodes use; BiSECt after the switch follows it by default."""
        ...

    def node_edge(self, node: int) -> int:
        """The edge to check at ``node``, or NO_EDGE at a leaf."""
        ...

    def node_child(self, node: int, free: bool) -> int:
        """The child for the outcome, or NO_CHILD."""
        ...

    def node_fraction(self, node: int) -> float:
        """The node's consistent prior mass as a fraction of the training mass."""
        ...

    def bias(self, node: int, *, alpha: float = 0.99) -> FloatArray:
        """(E,) BiSECt's bias at ``node``."""
        ...


def leaf_bias(
    num_edges: int, library_edges: IntArray, free_fraction: npt.NDArray[np.float32], *, alpha: float
) -> FloatArray:
    """(E,) theta = alpha * free fraction + (1 - alpha) / 2 on the library edges, 0.5 elsewhere."""
    theta = np.full(num_edges, 0.5)
    theta[library_edges] = alpha * free_fraction.astype(np.float64) + (1 - alpha) * 0.5
    return theta


def build_tree(
    problem: Problem,
    *,
    expand_threshold: float = DEFAULT_EXPAND_THRESHOLD,
    colouring: bool = False,
    top_regions: int | None = None,
    max_prob_region: bool = True,
    max_nodes: int = 100_000,
    progress: bool | None = None,
    region_rule: str = DEFAULT_REGION_RULE,
) -> DecisionTree:
    """Build the DiRECt decision tree on the problem's training worlds.

    Args:
        problem: a problem with a world database (its train_ids are the hypotheses).
        expand_threshold: a node is expanded only if its consistent fraction is >= this.
        colouring: use region colouring (fewer ECDs) in DiRECt.
        max_prob_region: restrict each node's candidate tests to the edges of the library path
            valid in the most consistent worlds (the DiRECt analogue of BiSECt's MaxProbReg; the
            gain is still the Noisy-OR over every ECD). Falls back to all tests when none of that
            path's edges splits the worlds. On by default: see the README's results.
        top_regions: None runs DiRECt on every library path; k runs the authors' IncDRD: DiRECt on
            k regions chosen by greedy cover of the consistent worlds (re-chosen when all k have
            lost their worlds), and once one of them holds every consistent world the tree checks
            that path's remaining edges in order (the region is "latched").
        max_nodes: safety cap on the number of nodes.
        progress: show a progress bar (None: only on a terminal).
        region_rule: which path ``max_prob_region`` restricts to
            (:data:`~drd_planner.core.region_rule.REGION_RULES`; the paper's: the best-supported path).
    """
    worlds = problem.require_worlds()
    train = worlds.train_ids
    if train.size == 0:
        raise ProblemError("cannot build a decision tree without training worlds")
    builder = _TreeBuilder(
        problem,
        colouring=colouring,
        top_regions=top_regions,
        max_prob_region=max_prob_region,
        region_rule=check_region_rule(region_rule),
    )
    t0 = time.perf_counter()
    expanded = builder.expand(expand_threshold=expand_threshold, max_nodes=max_nodes, progress=progress)
    build_s = time.perf_counter() - t0
    info = {
        "expand_threshold": expand_threshold,
        "colouring": colouring,
        "top_regions": top_regions,
        "max_prob_region": max_prob_region,
        "region_rule": region_rule,
        "num_train_worlds": int(train.size),
        "num_ecds": builder.selector.num_ecds,
        "null_ecd": builder.selector.has_null_ecd,
        "expanded_nodes": expanded,
        "build_seconds": build_s,
        "matmul_flops": builder.selector.matmul_flops,
    }
    return builder.tree(info)


class _TreeBuilder:
    """The growing tree of :func:`build_tree`: per node its edge, children, consistent worlds and parent.

    With ``top_regions`` (IncDRD) a node also carries its region subset and the latched region (-1: none).
    """

    def __init__(
        self,
        problem: Problem,
        *,
        colouring: bool,
        top_regions: int | None,
        max_prob_region: bool,
        region_rule: str = DEFAULT_REGION_RULE,
    ) -> None:
        """Prepare the training worlds of ``problem`` and DiRECt's selector (see :func:`build_tree`)."""
        worlds = problem.require_worlds()
        train = worlds.train_ids
        self.problem = problem
        self.top_regions = top_regions
        self.max_prob_region = max_prob_region
        self.X = worlds.X[train]
        self.R = worlds.R[train]
        self.prior = None if worlds.prior is None else worlds.prior[train]
        self.weights = np.ones(train.size) if self.prior is None else self.prior
        self.total = float(self.weights.sum())
        self.selector = DirectSelector(self.X, self.R, problem.edge_costs, prior=self.prior, colouring=colouring)
        self.r_float = self.R.astype(np.float64)
        self.region = (
            None
            if region_rule == DEFAULT_REGION_RULE
            else NodeRegionInputs(region_rule, self.X, problem.library, problem.edge_costs)
        )
        self.edges: list[int] = []
        self.children: list[list[int]] = []
        self.actives: list[IntArray] = []
        self.parents: list[int] = []
        self.subsets: list[IntArray | None] = []
        self.latched: list[int] = []

    def add_node(self, active: IntArray, parent: int, subset: IntArray | None, latch: int) -> int:
        """Append a leaf with the (k,) consistent training worlds ``active``; return its index."""
        self.edges.append(NO_EDGE)
        self.children.append([NO_CHILD, NO_CHILD])
        self.actives.append(active)
        self.parents.append(parent)
        self.subsets.append(subset)
        self.latched.append(latch)
        return len(self.edges) - 1

    def checked_on_branch(self, node: int) -> set[int]:
        """The edges checked on the way from the root to ``node``."""
        done: set[int] = set()
        while self.parents[node] >= 0:
            node = self.parents[node]
            done.add(self.edges[node])
        return done

    def choose(self, node: int) -> int | None:
        """The edge ``node`` checks, or None when it stays a leaf."""
        if self.top_regions is None:
            return direct_node_edge(
                self.selector,
                self.actives[node],
                self.weights,
                self.r_float,
                self.problem.library,
                max_prob_region=self.max_prob_region,
                region=self.region,
                checked=self._checked_mask(node) if self.region is not None else None,
            )
        return self._choose_incdrd(node, self.top_regions)

    def _checked_mask(self, node: int) -> BoolArray:
        """(E,) the edges checked on the way from the root to ``node``."""
        mask = np.zeros(self.problem.library.num_edges, dtype=bool)
        mask[list(self.checked_on_branch(node))] = True
        return mask

    def _choose_incdrd(self, node: int, top_regions: int) -> int | None:
        """IncDRD: DiRECt on ``top_regions`` greedy-cover regions, then the latched region's edges in order."""
        active = self.actives[node]
        R = self.R
        latch = self.latched[node]
        if latch < 0:
            subset = self.subsets[node]
            if subset is None or not R[np.ix_(active, subset)].any():
                subset = greedy_cover_regions(R[active], self.weights[active], top_regions)
                self.subsets[node] = subset
            if subset.size == 0:
                return None
            choice = self.selector.select(active, regions=subset)
            if choice is not None:
                return choice.edge
            certified = subset[R[np.ix_(active, subset)].all(axis=0)]
            if certified.size == 0:
                return None
            latch = int(certified[0])
            self.latched[node] = latch
        done = self.checked_on_branch(node)
        todo = [int(e) for e in self.problem.library.path_edges[latch] if int(e) not in done]
        return todo[0] if todo else None

    def expand(self, *, expand_threshold: float, max_nodes: int, progress: bool | None) -> int:
        """Grow the tree breadth-first from the root; return the number of expanded nodes."""
        queue: deque[int] = deque()
        queue.append(self.add_node(np.arange(self.X.shape[0], dtype=np.int64), -1, None, -1))
        expanded = 0
        with tqdm(desc="DiRECt tree", unit="node", disable=progress is False if progress is not None else None) as bar:
            while queue:
                node = queue.popleft()
                edge = self.choose(node)
                bar.update(1)
                if edge is None:
                    continue
                if len(self.edges) + 2 > max_nodes:
                    raise ProblemError(f"decision tree exceeds max_nodes={max_nodes}")
                expanded += 1
                self.edges[node] = edge
                queue.extend(self._split(node, edge, expand_threshold))
        return expanded

    def _split(self, node: int, edge: int, expand_threshold: float) -> list[int]:
        """Add ``node``'s children for the outcomes of ``edge``; return those heavy enough to expand."""
        active = self.actives[node]
        outcome = self.X[active, edge]
        heavy = []
        for x in (0, 1):
            child_active = active[outcome == bool(x)]
            child = self.add_node(child_active, node, self.subsets[node], self.latched[node] if x else -1)
            self.children[node][x] = child
            if float(self.weights[child_active].sum()) / self.total >= expand_threshold:
                heavy.append(child)
        return heavy

    def tree(self, info: dict[str, Any]) -> DecisionTree:
        """The finished :class:`DecisionTree` with per-node summaries and the build ``info``."""
        lib_edges = self.problem.library.library_edges
        x_lib = self.X[:, lib_edges].astype(np.float64)
        weights, total = self.weights, self.total
        n_nodes = len(self.edges)
        num_active = np.array([a.size for a in self.actives], dtype=np.int32)
        active_fraction = np.array([weights[a].sum() / total for a in self.actives], dtype=np.float64)
        free_fraction = np.full((n_nodes, lib_edges.size), 0.5, dtype=np.float32)
        best_path = np.full(n_nodes, -1, dtype=np.int32)
        for node, active in enumerate(self.actives):
            if active.size:
                free_fraction[node], best_path[node] = node_summary(
                    weights[active], x_lib[active], self.r_float[active]
                )
        return DecisionTree(
            edge=np.array(self.edges, dtype=np.int32),
            children=np.array(self.children, dtype=np.int32).reshape(-1, 2),
            num_active=num_active,
            active_fraction=active_fraction,
            library_edges=lib_edges,
            free_fraction=free_fraction,
            best_path=best_path,
            num_edges=self.problem.num_edges,
            num_paths=self.problem.num_paths,
            info=info,
            world_free=np.ascontiguousarray(self.X[:, lib_edges], dtype=bool),
            world_weights=None if self.prior is None else np.asarray(self.prior, dtype=np.float64),
        )


def direct_node_edge(
    selector: DirectSelector,
    active: IntArray,
    weights: FloatArray,
    r_float: FloatArray,
    library: PathLibrary,
    *,
    max_prob_region: bool,
    region: NodeRegionInputs | None = None,
    checked: BoolArray | None = None,
) -> int | None:
    """The DiRECt edge of a tree node whose consistent training worlds are ``active`` (or None: a leaf).

    The one node rule shared by the offline tree (:func:`build_tree`) and the tree grown online
    (:class:`drd_planner.core.online_tree.LazyDirectTree`), so both ask for the same edges.

    Args:
        selector: DiRECt over the training worlds.
        active: (k,) int64 row ids of the consistent training worlds.
        weights: (n,) prior weights of all training worlds.
        r_float: (n, m) float64 path validity of all training worlds.
        library: the m paths.
        max_prob_region: restrict the tests to the edges of the best-supported path (falling back to
            every test when none of them splits the worlds).
        region: what the ``per_check`` region rule needs (None: the paper's rule, the path valid in the
            most consistent worlds).
        checked: (E,) bool edges checked on the way from the root to the node (``per_check`` only).
    """
    candidates = None
    if max_prob_region:
        support = weights[active] @ r_float[active]
        if region is None or region.rule == "probability":
            best = int(np.argmax(support)) if support.max() > 0 else None
        else:
            done = np.zeros(library.num_edges, dtype=bool) if checked is None else checked
            best = region.path(support, active, weights, done)
        if best is not None:
            candidates = library.path_edges[best]
    choice = selector.select(active, candidates=candidates)
    if choice is None and candidates is not None:
        choice = selector.select(active)
    return None if choice is None else choice.edge


def node_summary(
    weights: FloatArray, x_lib: npt.NDArray[np.floating], r_float: FloatArray
) -> tuple[npt.NDArray[np.float32], int]:
    """A non-empty node's leaf bias data and DiRECt-only guess.

    Args:
        weights: (k,) prior weights of the node's worlds (positive sum).
        x_lib: (k, K) outcomes of the library edges in those worlds.
        r_float: (k, m) path validity in those worlds.

    Returns:
        ``(free_fraction, best_path)``: (K,) float32 weighted free fraction of each library edge, and
        the path valid in the most weight (-1 when none is valid in any of them).
    """
    free = np.asarray((weights @ x_lib) / weights.sum(), dtype=np.float32)
    support = weights @ r_float
    return free, int(np.argmax(support)) if support.max() > 0 else -1


def greedy_cover_regions(R: npt.ArrayLike, weights: npt.ArrayLike, k: int) -> IntArray:
    """Up to k regions by greedy cover: the region with most (weighted) worlds, drop them, repeat.

    Args:
        R: (n, m) bool membership of the consistent worlds.
        weights: (n,) their prior weights.
        k: how many regions to pick.

    Returns:
        (<= k,) int64 region ids, in the order picked; fewer when no region covers what is left.
    """
    r = np.asarray(R, dtype=bool)
    w = np.asarray(weights, dtype=np.float64).copy()
    picked: list[int] = []
    for _ in range(k):
        support = w @ r
        best = int(np.argmax(support))
        if support[best] <= 0:
            break
        picked.append(best)
        w[r[:, best]] = 0.0
    return np.array(picked, dtype=np.int64)
