"""Exact optima under the independent-edge model, x_e ~ Bernoulli(theta_e) (docs/algorithms.md).

* :func:`exact_bernoulli_optimum` -- the episode problem as sequential Boolean function evaluation
  (SBFE) of the monotone DNF OR_i AND_{e in path i} x_e, by DP over partial assignments.
* :func:`expected_policy_cost_bernoulli` -- the exact expected cost of a given deterministic policy,
  to compare with the optimum.

Exponential on purpose (at most :data:`~drd_planner.bench.optima_support.MAX_LIBRARY_EDGES` library
edges); used by benchmarks and tests, never by the planner. Sets of edges and paths are ``int`` bitmasks.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.bench.optima_support import (
    MAX_POLICY_NODES,
    PathsLike,
    SelectorFactory,
    bits,
    check_costs,
    check_library,
    check_theta,
    local_path_masks,
)
from drd_planner.exceptions import PolicyError, ProblemError

__all__ = ["exact_bernoulli_optimum", "expected_policy_cost_bernoulli"]


class _SbfeSolver:
    """Memoised V(s) of :func:`exact_bernoulli_optimum` over collapsed partial assignments."""

    def __init__(self, path_masks: list[int], local_theta: list[float], local_costs: list[float]) -> None:
        """Per path its local edge mask; (K,) P(free) and costs of the library edges."""
        self.path_masks = path_masks
        self.local_theta = local_theta
        self.local_costs = local_costs
        self.order = sorted(range(len(local_costs)), key=local_costs.__getitem__)
        self.memo: dict[tuple[int, int, int], float] = {}

    def union(self, alive: int, free: int) -> int | None:
        """Edges of the alive paths; None when one of them is all free (f is determined true)."""
        union = 0
        for i in bits(alive):
            pm = self.path_masks[i]
            if pm & free == pm:
                return None
            union |= pm
        return union

    def value(self, alive: int, known: int, free: int) -> float:
        """alive: bitmask of path ids; known/free: bitmasks of local edges (free within known)."""
        union = self.union(alive, free)
        if not union:  # None (a path proven free) or 0 (every path blocked)
            return 0.0
        known &= union
        free &= union
        key = (alive, known, free)
        cached = self.memo.get(key)
        if cached is not None:
            return cached
        best = math.inf
        unknown = union & ~known
        for j in self.order:
            bit = 1 << j
            if not unknown & bit:
                continue
            c = self.local_costs[j]
            if c >= best:
                break
            q = self.local_theta[j]
            v = c
            if q > 0.0:
                v += q * self.value(alive, known | bit, free | bit)
            if q < 1.0 and v < best:
                dead = sum(1 << i for i in bits(alive) if self.path_masks[i] & bit)
                v += (1.0 - q) * self.value(alive & ~dead, known | bit, free)
            best = min(best, v)
        self.memo[key] = best
        return best


def exact_bernoulli_optimum(
    paths: PathsLike,
    theta: npt.ArrayLike,
    edge_costs: npt.ArrayLike,
) -> float:
    """Optimal expected episode cost when edges are independent, x_e ~ Bernoulli(theta_e) (8.2).

    This is sequential Boolean function evaluation (SBFE) of f(x) = OR_i AND_{e in path i} x_e.
    DP over partial assignments s of the library edges (each edge 0, 1 or unknown):

        V(s) = 0 if f is determined (some path all 1, or every path has a 0), else
        V(s) = min_e c(e) + theta_e V(s, e=1) + (1 - theta_e) V(s, e=0)

    over unknown edges e of alive paths. States are collapsed to (alive paths, outcomes of the
    edges of alive paths): what is known about other edges no longer matters. Branches of
    probability 0 (theta_e in {0, 1}) are skipped.

    Args:
        paths: m library paths, each a sequence of distinct edge ids in [0, E).
        theta: (E,) P(edge free).
        edge_costs: (E,) positive check costs.

    Returns:
        The optimal expected cost, >= 0.

    Raises:
        ProblemError: bad inputs, or more than MAX_LIBRARY_EDGES distinct library edges.
    """
    th = check_theta(theta)
    costs = check_costs(edge_costs, th.size)
    library = check_library(paths, th.size)
    edges, path_masks = local_path_masks(library)
    solver = _SbfeSolver(path_masks, [float(th[e]) for e in edges], [float(costs[e]) for e in edges])
    return float(solver.value((1 << len(path_masks)) - 1, 0, 0))


class _PolicyTree:
    """Expands a deterministic policy's decision tree over the outcomes of the edges it chooses."""

    def __init__(
        self,
        path_sets: list[list[int]],
        theta: FloatArray,
        costs: FloatArray,
        make_selector: SelectorFactory,
        max_nodes: int,
    ) -> None:
        """Library paths as edge lists, (E,) P(free) and costs, the selector factory, the node limit."""
        self.path_sets = path_sets
        self.theta = theta
        self.costs = costs
        self.make_selector = make_selector
        self.max_nodes = max_nodes
        self.visited = 0

    def determined(self, obs: Mapping[int, bool]) -> bool:
        """Some path proven free, or every path blocked."""
        all_blocked = True
        for p in self.path_sets:
            outcomes = [obs.get(e) for e in p]
            if False in outcomes:
                continue
            if None not in outcomes:
                return True  # every edge checked free
            all_blocked = False
        return all_blocked

    def choose(self, obs: dict[int, bool]) -> int | None:
        """The policy's edge after ``obs``; PolicyError for an edge outside [0, E) or a repeat."""
        choice = self.make_selector(dict(obs)).select()
        if choice is None:
            return None
        e = int(choice)
        if not 0 <= e < self.theta.size:
            raise PolicyError(f"the policy chose edge {e}, outside [0, {self.theta.size})")
        if e in obs:
            raise PolicyError(f"the policy chose edge {e} a second time")
        return e

    def value(self, obs: dict[int, bool]) -> float:
        """Expected cost of the subtree after the observations ``obs``."""
        self.visited += 1
        if self.visited > self.max_nodes:
            raise ProblemError(f"the policy's decision tree has more than {self.max_nodes} nodes")
        if self.determined(obs):
            return 0.0
        e = self.choose(obs)
        if e is None:
            return 0.0
        q = float(self.theta[e])
        v = float(self.costs[e])
        if q > 0.0:
            v += q * self.value({**obs, e: True})
        if q < 1.0:
            v += (1.0 - q) * self.value({**obs, e: False})
        return v


def expected_policy_cost_bernoulli(
    paths: PathsLike,
    theta: npt.ArrayLike,
    edge_costs: npt.ArrayLike,
    make_selector: SelectorFactory,
    *,
    max_nodes: int = MAX_POLICY_NODES,
) -> float:
    """Exact expected cost of a deterministic policy under the independent-edge model.

    The policy's decision tree is expanded over the outcomes of the edges it chooses. At every
    node a fresh selector is built by ``make_selector(observations)`` (edge -> free, the outcomes
    on the way from the root) and asked ``select()``. A node is a leaf when the episode has ended
    (some path proven free or every path blocked) or the policy returns None. For example, with
    ``library = PathLibrary.from_sequences(paths, E)``::

        make_selector = lambda obs: Bisect(library, theta, costs, max_prob_region=True, observations=obs)

    The policy must be deterministic given the observations (their order aside).

    Args:
        paths: m library paths, each a sequence of distinct edge ids in [0, E).
        theta: (E,) P(edge free).
        edge_costs: (E,) positive check costs.
        make_selector: builds a selector that has heard the given observations.
        max_nodes: refuse (ProblemError) when the tree has more nodes than this.

    Returns:
        sum over leaves of P(leaf) * (cost of the checks on the way to it).

    Raises:
        ProblemError: bad inputs, more than MAX_LIBRARY_EDGES library edges, or too large a tree.
        PolicyError: the policy chose an edge outside [0, E) or one already observed.
    """
    th = check_theta(theta)
    costs = check_costs(edge_costs, th.size)
    library = check_library(paths, th.size)
    path_sets = [[int(e) for e in p] for p in library.path_edges]
    return float(_PolicyTree(path_sets, th, costs, make_selector, max_nodes).value({}))
