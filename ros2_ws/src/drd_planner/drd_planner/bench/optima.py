"""Exact optima on a finite world database (docs/algorithms.md, "Bounds and exact optima").

Everything here is exponential on purpose and refuses instances that are too large with a
:class:`~drd_planner.exceptions.ProblemError`. Benchmarks and tests use it to measure how far the greedy
policies (DiRECt, BiSECt) are from the Bayes-optimal policy on tiny instances; the planner never does.

* :func:`exact_drd_optimum` -- the finite-database DRD problem (8.3): the optimal expected cost of
  *deciding* which region the true world lies in, by memoised recursion over version spaces.
* :func:`exact_episode_optimum` -- the episode problem on a finite database: the optimal expected
  cost of *verifying* a library path (or refuting all of them), as every benchmark episode must.
* :func:`expected_policy_cost_database` -- the prior-weighted cost a given policy pays on the database.

The independent-edge counterparts are in :mod:`drd_planner.bench.optima_bernoulli`, the verification
lower bound in :mod:`drd_planner.core.bounds`. Sets of worlds and of edges are ``int`` bitmasks.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray
from drd_planner.bench.optima_support import (
    MAX_DRD_WORLDS,
    MAX_EPISODE_WORLDS,
    PathsLike,
    WorldMass,
    bits,
    check_costs,
    check_library,
    check_prior,
    column_masks,
    local_path_masks,
    path_library,
)
from drd_planner.core.bounds import bool_matrix
from drd_planner.exceptions import ProblemError

__all__ = ["exact_drd_optimum", "exact_episode_optimum", "expected_policy_cost_database"]


# --------------------------------------------------------------------------------------------------
# 8.3 finite-database DRD optimum
# --------------------------------------------------------------------------------------------------


class _DrdSolver:
    """Memoised V(H') of :func:`exact_drd_optimum` over version spaces H' (bitmasks of kept worlds)."""

    def __init__(self, x: BoolArray, r: BoolArray, costs: FloatArray, weights: FloatArray) -> None:
        """(n, E) tests ``x``, (n, m) regions ``r``, (E,) costs and (n,) positive weights."""
        self.mass = WorldMass(weights)
        self.full = (1 << x.shape[0]) - 1
        # Tests with the same outcome split cost the cheapest of them.
        cheapest: dict[int, float] = {}
        for tmask, c in zip(column_masks(x), costs.tolist(), strict=True):
            if 0 < tmask < self.full and cheapest.get(tmask, math.inf) > c:
                cheapest[tmask] = c
        self.tests = sorted(cheapest.items(), key=lambda item: item[1])
        self.regions = sorted({m for m in column_masks(r) if m})
        any_valid = 0
        for m in self.regions:
            any_valid |= m
        self.any_valid = any_valid
        self.memo: dict[int, float] = {}

    def decided(self, h: int) -> bool:
        """H' lies in no region, or all of it in one common region."""
        return h & self.any_valid == 0 or any(h & ~reg == 0 for reg in self.regions)

    def splits(self, h: int) -> dict[int, float]:
        """Unordered informative partitions {H'_0, H'_1} (keyed by the smaller mask) -> cheapest cost.

        In increasing cost order (tests are sorted by cost: the first of a partition is its cheapest).
        """
        out: dict[int, float] = {}
        for tmask, c in self.tests:
            h1 = h & tmask
            if h1 in (0, h):
                continue
            key = min(h1, h ^ h1)
            if key not in out:
                out[key] = c
        return out

    def value(self, h: int) -> float:
        """V(H'), the optimal expected cost from version space ``h``."""
        cached = self.memo.get(h)
        if cached is not None:
            return cached
        if self.decided(h):
            self.memo[h] = 0.0
            return 0.0
        ph = self.mass(h)
        best = math.inf
        for part, c in self.splits(h).items():  # insertion order = increasing cost
            if c >= best:
                break
            other = h ^ part
            p_part = self.mass(part) / ph
            v = c + p_part * self.value(part)
            if v < best:
                v += (1.0 - p_part) * self.value(other)
            best = min(best, v)
        result = 0.0 if best == math.inf else best
        self.memo[h] = result
        return result


def exact_drd_optimum(
    X: npt.ArrayLike,
    R: npt.ArrayLike,
    edge_costs: npt.ArrayLike,
    prior: npt.ArrayLike | None = None,
) -> float:
    """Bayes-optimal expected cost of the finite-database DRD problem (docs/algorithms.md, "Bounds").

    Version spaces H' (sets of worlds consistent with the outcomes so far) are bitmasks. With
    P the prior restricted to H',

        V(H') = 0                                  if H' is *decided* (below),
        V(H') = min_t c(t) + sum_x P(H'_x) / P(H') V(H'_x)   over informative tests t,

    where t is informative when both outcome sets H'_0, H'_1 are non-empty. H' is decided when

    * all worlds of H' lie in one common region (some path is valid in every one of them), or
    * H' lies in no region (no world of H' has any valid path), or
    * all worlds of H' have identical R rows (one *atom*). This is DiRECt's stopping rule (variant
      (b)); it is implied by the two rules above (an all-False row is the second rule, any other
      row the first), so it needs no separate test.

    When H' is not decided but no test is informative (possible only if R is not a function of
    X), nothing more can be learnt and V(H') = 0, as :class:`DirectSelector` also stops there.

    Worlds with zero prior weight are dropped. The result is the expectation under the prior over
    all n worlds (normalised); it never counts uninformative tests, so it is a decision cost, not
    an episode (verification) cost -- see :func:`exact_episode_optimum` for that.

    Args:
        X: (n, E) bool test outcomes per world.
        R: (n, m) bool region (path) membership per world.
        edge_costs: (E,) positive test costs.
        prior: (n,) non-negative prior weights, or None for uniform.

    Returns:
        The optimal expected cost, >= 0.

    Raises:
        ProblemError: inconsistent shapes, bad costs or prior, or n > MAX_DRD_WORLDS.
    """
    x = bool_matrix("X", X)
    r = bool_matrix("R", R)
    n = x.shape[0]
    if r.shape[0] != n:
        raise ProblemError(f"X has {n} worlds but R has {r.shape[0]}")
    if n == 0:
        raise ProblemError("exact_drd_optimum needs at least one world")
    if n > MAX_DRD_WORLDS:
        raise ProblemError(
            f"exact_drd_optimum is exponential in the number of worlds: {n} > {MAX_DRD_WORLDS}; sub-sample the database"
        )
    costs = check_costs(edge_costs, x.shape[1])
    weights = check_prior(prior, n)
    keep = weights > 0
    solver = _DrdSolver(x[keep], r[keep], costs, weights[keep])
    return float(solver.value(solver.full))


# --------------------------------------------------------------------------------------------------
# episode optimum on a finite database
# --------------------------------------------------------------------------------------------------


class _EpisodeSolver:
    """Memoised V(A, H') of :func:`exact_episode_optimum` (checked local edges A, version space H')."""

    def __init__(self, x: BoolArray, path_masks: list[int], local_costs: list[float], weights: FloatArray) -> None:
        """(n, K) outcomes of the K library edges, per path its local edge mask, (K,) costs, (n,) weights."""
        self.path_masks = path_masks
        self.local_costs = local_costs
        self.mass = WorldMass(weights)
        self.world_masks = column_masks(x)  # per local edge: worlds where it is free
        self.free_bits = [sum(1 << j for j in np.flatnonzero(row).tolist()) for row in x]  # per world
        self.memo: dict[tuple[int, int, int], float] = {}

    def alive(self, checked: int, h: int) -> tuple[int, int] | None:
        """(union of the alive paths' edges, alive paths mask); None when some path is proven free."""
        rep = (h & -h).bit_length() - 1  # any world of H': they agree on the checked edges
        free = checked & self.free_bits[rep]
        blocked = checked & ~self.free_bits[rep]
        union = 0
        alive = 0
        for i, pm in enumerate(self.path_masks):
            if pm & blocked == 0:
                if pm & free == pm:
                    return None
                union |= pm
                alive |= 1 << i
        return union, alive

    def value(self, checked: int, h: int) -> float:
        """V(A, H'), the optimal expected cost to end the episode from this state."""
        state = self.alive(checked, h)
        if state is None or state[0] == 0:
            return 0.0
        union, alive = state
        # Checks off the alive paths no longer matter (the alive set is part of the key).
        key = (alive, checked & union, h)
        cached = self.memo.get(key)
        if cached is not None:
            return cached
        ph = self.mass(h)
        best = math.inf
        for j in sorted(bits(union & ~checked), key=self.local_costs.__getitem__):
            c = self.local_costs[j]
            if c >= best:
                break
            nxt = checked | (1 << j)
            h1 = h & self.world_masks[j]
            h0 = h ^ h1
            if h0 == 0 or h1 == 0:
                v = c + self.value(nxt, h)
            else:
                p1 = self.mass(h1) / ph
                v = c + p1 * self.value(nxt, h1)
                if v < best:
                    v += (1.0 - p1) * self.value(nxt, h0)
            best = min(best, v)
        self.memo[key] = best
        return best


def exact_episode_optimum(
    X: npt.ArrayLike,
    paths: PathsLike,
    edge_costs: npt.ArrayLike,
    prior: npt.ArrayLike | None = None,
) -> float:
    """Bayes-optimal expected cost of a benchmark *episode* on a finite world database.

    An episode ends when some library path has every edge checked free, or every library path has
    a checked blocked edge (docs/algorithms.md, "The problem"). The state is (checked edges, version space
    H'); all worlds of H' agree on the checked edges. From a state that has not ended, checking
    any unchecked edge e of a still-alive path -- informative on H' or not, since verification
    needs uninformative edges too -- costs c(e) and splits H' by the outcome of e:

        V(A, H') = 0 if the episode has ended, else
        V(A, H') = min_e c(e) + sum_x P(H'_x) / P(H') V(A + e, H'_x).

    This is never below :func:`exact_drd_optimum` with R derived from X and ``paths`` (an episode
    policy also decides the region), nor below the prior mean of
    :func:`~drd_planner.core.bounds.oracle_lower_bound`.

    Args:
        X: (n, E) bool edge outcomes per world.
        paths: m library paths, each a sequence of distinct edge ids in [0, E).
        edge_costs: (E,) positive check costs.
        prior: (n,) non-negative prior weights, or None for uniform.

    Returns:
        The optimal expected episode cost under the (normalised) prior, >= 0.

    Raises:
        ProblemError: bad shapes, costs, prior or paths, n > MAX_EPISODE_WORLDS, or more than
            MAX_LIBRARY_EDGES distinct library edges.
    """
    x = bool_matrix("X", X)
    n, num_edges = x.shape
    if n == 0:
        raise ProblemError("exact_episode_optimum needs at least one world")
    if n > MAX_EPISODE_WORLDS:
        raise ProblemError(f"exact_episode_optimum is exponential in the number of worlds: {n} > {MAX_EPISODE_WORLDS}")
    costs = check_costs(edge_costs, num_edges)
    weights = check_prior(prior, n)
    library = check_library(paths, num_edges)
    edges, path_masks = local_path_masks(library)
    keep = weights > 0
    x, weights = x[keep], weights[keep]
    solver = _EpisodeSolver(x[:, edges], path_masks, [float(costs[e]) for e in edges], weights)
    return float(solver.value(0, (1 << x.shape[0]) - 1))


# --------------------------------------------------------------------------------------------------
# expected cost of a given policy
# --------------------------------------------------------------------------------------------------


def expected_policy_cost_database(
    X: npt.ArrayLike,
    paths: PathsLike,
    edge_costs: npt.ArrayLike,
    run_one: Callable[[int], int | float],
    prior: npt.ArrayLike | None = None,
) -> float:
    """Prior-weighted mean over the worlds of a database of the cost a policy paid on each.

    ``X``, ``paths`` and ``edge_costs`` only validate the instance; ``run_one(h)`` runs the policy
    on world h (row h of X) and returns its cost. Worlds of zero prior weight are not run.

    Args:
        X: (n, E) bool edge outcomes per world.
        paths: m library paths, each a sequence of distinct edge ids in [0, E).
        edge_costs: (E,) positive check costs.
        run_one: world index -> cost paid (finite, >= 0).
        prior: (n,) non-negative prior weights, or None for uniform.

    Returns:
        sum_h prior_h run_one(h) / sum_h prior_h.

    Raises:
        ProblemError: bad inputs, or ``run_one`` returned a negative or non-finite cost.
    """
    x = bool_matrix("X", X)
    n, num_edges = x.shape
    if n == 0:
        raise ProblemError("expected_policy_cost_database needs at least one world")
    check_costs(edge_costs, num_edges)
    path_library(paths, num_edges)
    weights = check_prior(prior, n)
    total = 0.0
    for h in np.flatnonzero(weights > 0).tolist():
        cost = float(run_one(h))
        if not math.isfinite(cost) or cost < 0:
            raise ProblemError(f"run_one({h}) returned {cost}; costs must be finite and >= 0")
        total += float(weights[h]) * cost
    return total / float(weights.sum())
