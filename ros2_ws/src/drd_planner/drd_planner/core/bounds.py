"""Exact optima and lower bounds for small instances (ALGORITHMS.md section 8, the "physical limit").

Everything here is exponential on purpose and refuses instances that are too large with a
:class:`~drd_planner.exceptions.ProblemError`. The functions measure how far the greedy policies
(DiRECt, BiSECt) are from the Bayes-optimal policy on tiny instances:

* :func:`oracle_lower_bound` -- the verification lower bound (8.1): per world the cost of its
  cheapest valid library path. Cheap, valid for any size.
* :func:`exact_drd_optimum` -- the finite-database DRD problem (8.3): the optimal expected cost of
  *deciding* which region the true world lies in, by memoised recursion over version spaces.
* :func:`exact_episode_optimum` -- the episode problem on a finite database: the optimal expected
  cost of *verifying* a library path (or refuting all of them), as every benchmark episode must.
* :func:`exact_bernoulli_optimum` -- the episode problem under the independent-edge model, i.e.
  SBFE of the monotone DNF OR_i AND_{e in path i} x_e (8.2), by DP over partial assignments.
* :func:`expected_policy_cost_bernoulli` / :func:`expected_policy_cost_database` -- the exact
  expected cost of a given deterministic policy, to compare with the optima above.

Sets of worlds and sets of edges are Python ``int`` bitmasks (bit j set = member j), which makes
the memo keys hashable and the set operations cheap.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray
from drd_planner.core.library import PathLibrary
from drd_planner.exceptions import PolicyError, ProblemError

#: Library paths: per path its edge ids, as a sequence of ints or an integer array.
PathsLike = Sequence[Sequence[int] | npt.NDArray[np.integer[Any]]]

#: Largest database :func:`exact_drd_optimum` accepts (version spaces are subsets of the worlds).
MAX_DRD_WORLDS = 24
#: Largest database :func:`exact_episode_optimum` accepts.
MAX_EPISODE_WORLDS = 16
#: Most library edges (edges on at least one path) the episode DPs and policy evaluation accept.
MAX_LIBRARY_EDGES = 16
#: Default limit on the number of decision-tree nodes :func:`expected_policy_cost_bernoulli` visits.
MAX_POLICY_NODES = 1_000_000


class EdgeSelector(Protocol):
    """Anything with a ``select`` method, e.g. :class:`drd_planner.core.bisect.Bisect`."""

    def select(self) -> int | None:
        """The next edge to check, or None when the policy stops."""
        ...


#: Builds a fresh selector that has already heard ``observations`` (edge -> free).
SelectorFactory = Callable[[dict[int, bool]], EdgeSelector]


# --------------------------------------------------------------------------------------------------
# input validation
# --------------------------------------------------------------------------------------------------


def _bool_matrix(name: str, a: npt.ArrayLike) -> BoolArray:
    arr = np.asarray(a)
    if arr.ndim != 2:
        raise ProblemError(f"{name} must be a 2-D array, got shape {arr.shape}")
    if arr.dtype != np.bool_ and arr.size and not np.all((arr == 0) | (arr == 1)):
        raise ProblemError(f"{name} must hold only 0/1 (or bool) values")
    return np.asarray(arr, dtype=bool)


def _costs(edge_costs: npt.ArrayLike, num_edges: int) -> FloatArray:
    costs = np.asarray(edge_costs, dtype=np.float64)
    if costs.shape != (num_edges,):
        raise ProblemError(f"edge_costs must have shape ({num_edges},), got {costs.shape}")
    if not np.all(np.isfinite(costs)) or np.any(costs <= 0):
        raise ProblemError("edge_costs must be finite and positive")
    return costs


def _prior(prior: npt.ArrayLike | None, n: int) -> FloatArray:
    if prior is None:
        return np.ones(n)
    w = np.asarray(prior, dtype=np.float64)
    if w.shape != (n,):
        raise ProblemError(f"prior must have shape ({n},), got {w.shape}")
    if not np.all(np.isfinite(w)) or np.any(w < 0) or not w.sum() > 0:
        raise ProblemError("prior must be finite, non-negative and have a positive sum")
    return w


def _theta(theta: npt.ArrayLike) -> FloatArray:
    th = np.asarray(theta, dtype=np.float64)
    if th.ndim != 1:
        raise ProblemError(f"theta must be a 1-D array, got shape {th.shape}")
    if not np.all((th >= 0) & (th <= 1)):
        raise ProblemError("theta must hold probabilities in [0, 1]")
    return th


def _path_library(paths: PathsLike, num_edges: int) -> PathLibrary:
    """A PathLibrary from ``paths`` (raises ProblemError for non-integer ids and bad paths)."""
    lists: list[list[int]] = []
    for i, p in enumerate(paths):
        arr = np.asarray(p).ravel()
        if arr.size and not np.issubdtype(arr.dtype, np.integer):
            raise ProblemError(f"library path {i} must list integer edge ids, got dtype {arr.dtype}")
        lists.append([int(e) for e in arr.tolist()])
    return PathLibrary.from_sequences(lists, num_edges)


def _library(paths: PathsLike, num_edges: int) -> PathLibrary:
    """Validate ``paths`` (raises ProblemError) and refuse more than MAX_LIBRARY_EDGES library edges."""
    library = _path_library(paths, num_edges)
    k = library.library_edges.size
    if k > MAX_LIBRARY_EDGES:
        raise ProblemError(
            f"the library uses {k} distinct edges; exact evaluation is limited to {MAX_LIBRARY_EDGES}"
        )
    return library


def _local_path_masks(library: PathLibrary) -> tuple[list[int], list[int]]:
    """(library edge ids in increasing order, per path the bitmask of its local edge indices)."""
    edges = [int(e) for e in library.library_edges]
    local = {e: j for j, e in enumerate(edges)}
    masks = [sum(1 << local[int(e)] for e in p) for p in library.path_edges]
    return edges, masks


class _Mass:
    """Prior mass of a bitmask of worlds by byte-wise lookup tables (exact for integer weights)."""

    def __init__(self, weights: FloatArray) -> None:
        self._tables: list[list[float]] = []
        for start in range(0, weights.size, 8):
            chunk = [float(v) for v in weights[start : start + 8]]
            table = [0.0] * 256
            for byte in range(1, 256):
                low = (byte & -byte).bit_length() - 1
                table[byte] = table[byte & (byte - 1)] + (chunk[low] if low < len(chunk) else 0.0)
            self._tables.append(table)

    def __call__(self, mask: int) -> float:
        total = 0.0
        for table in self._tables:
            total += table[mask & 255]
            mask >>= 8
        return total


def _bits(mask: int) -> list[int]:
    """Indices of the set bits of ``mask``, increasing."""
    out = []
    while mask:
        low = mask & -mask
        out.append(low.bit_length() - 1)
        mask ^= low
    return out


def _column_masks(x: BoolArray) -> list[int]:
    """Per column of (n, E) ``x`` the bitmask of the rows where it is True."""
    weights = [1 << h for h in range(x.shape[0])]
    return [sum(w for w, v in zip(weights, col, strict=True) if v) for col in x.T.tolist()]


# --------------------------------------------------------------------------------------------------
# 8.1 oracle lower bound
# --------------------------------------------------------------------------------------------------


def oracle_lower_bound(R: npt.ArrayLike, path_costs: npt.ArrayLike) -> FloatArray:
    """Per world the cost of its cheapest valid library path (the verification bound, 8.1).

    Any policy that ends an episode by proving a path free has checked every edge of that path,
    so its cost on world h is at least this value; the prior-weighted mean over worlds bounds
    every policy's expected cost from below.

    Args:
        R: (k, m) bool, R[h, i] = path i is valid in world h.
        path_costs: (m,) float, the cost of checking every edge of each path.

    Returns:
        (k,) float64 cheapest valid path cost per world; NaN for worlds with no valid path.
    """
    r = _bool_matrix("R", R)
    costs = np.asarray(path_costs, dtype=np.float64)
    if costs.shape != (r.shape[1],):
        raise ProblemError(f"path_costs must have shape ({r.shape[1]},), got {costs.shape}")
    if not np.all(np.isfinite(costs)) or np.any(costs < 0):
        raise ProblemError("path_costs must be finite and non-negative")
    if r.shape[1] == 0:
        return np.full(r.shape[0], np.nan)
    best = np.where(r, costs[None, :], np.inf).min(axis=1)
    return np.asarray(np.where(np.isfinite(best), best, np.nan), dtype=np.float64)


# --------------------------------------------------------------------------------------------------
# 8.3 finite-database DRD optimum
# --------------------------------------------------------------------------------------------------


def exact_drd_optimum(
    X: npt.ArrayLike,
    R: npt.ArrayLike,
    edge_costs: npt.ArrayLike,
    prior: npt.ArrayLike | None = None,
) -> float:
    """Bayes-optimal expected cost of the finite-database DRD problem (ALGORITHMS.md 8.3).

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
    x = _bool_matrix("X", X)
    r = _bool_matrix("R", R)
    n = x.shape[0]
    if r.shape[0] != n:
        raise ProblemError(f"X has {n} worlds but R has {r.shape[0]}")
    if n == 0:
        raise ProblemError("exact_drd_optimum needs at least one world")
    if n > MAX_DRD_WORLDS:
        raise ProblemError(
            f"exact_drd_optimum is exponential in the number of worlds: {n} > {MAX_DRD_WORLDS}; "
            "sub-sample the database"
        )
    costs = _costs(edge_costs, x.shape[1])
    weights = _prior(prior, n)
    keep = weights > 0
    x, r, weights = x[keep], r[keep], weights[keep]
    mass = _Mass(weights)
    full = (1 << x.shape[0]) - 1

    # Tests with the same outcome split cost the cheapest of them.
    cheapest: dict[int, float] = {}
    for tmask, c in zip(_column_masks(x), costs.tolist(), strict=True):
        if 0 < tmask < full and cheapest.get(tmask, math.inf) > c:
            cheapest[tmask] = c
    tests = sorted(cheapest.items(), key=lambda item: item[1])
    regions = sorted({m for m in _column_masks(r) if m})
    any_valid = 0
    for m in regions:
        any_valid |= m
    memo: dict[int, float] = {}

    def value(h: int) -> float:
        cached = memo.get(h)
        if cached is not None:
            return cached
        if h & any_valid == 0 or any(h & ~reg == 0 for reg in regions):
            memo[h] = 0.0
            return 0.0
        ph = mass(h)
        splits: dict[int, float] = {}
        for tmask, c in tests:
            h1 = h & tmask
            if h1 == 0 or h1 == h:
                continue
            key = min(h1, h ^ h1)  # the unordered partition {H'_0, H'_1}
            if key not in splits:  # tests are sorted by cost: the first is the cheapest
                splits[key] = c
        best = math.inf
        for part, c in splits.items():  # insertion order = increasing cost
            if c >= best:
                break
            other = h ^ part
            p_part = mass(part) / ph
            v = c + p_part * value(part)
            if v < best:
                v += (1.0 - p_part) * value(other)
            best = min(best, v)
        result = 0.0 if best == math.inf else best
        memo[h] = result
        return result

    return float(value(full))


# --------------------------------------------------------------------------------------------------
# episode optimum on a finite database
# --------------------------------------------------------------------------------------------------


def exact_episode_optimum(
    X: npt.ArrayLike,
    paths: PathsLike,
    edge_costs: npt.ArrayLike,
    prior: npt.ArrayLike | None = None,
) -> float:
    """Bayes-optimal expected cost of a benchmark *episode* on a finite world database.

    An episode ends when some library path has every edge checked free, or every library path has
    a checked blocked edge (ALGORITHMS.md section 1). The state is (checked edges, version space
    H'); all worlds of H' agree on the checked edges. From a state that has not ended, checking
    any unchecked edge e of a still-alive path -- informative on H' or not, since verification
    needs uninformative edges too -- costs c(e) and splits H' by the outcome of e:

        V(A, H') = 0 if the episode has ended, else
        V(A, H') = min_e c(e) + sum_x P(H'_x) / P(H') V(A + e, H'_x).

    This is never below :func:`exact_drd_optimum` with R derived from X and ``paths`` (an episode
    policy also decides the region), nor below the prior mean of :func:`oracle_lower_bound`.

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
    x = _bool_matrix("X", X)
    n, num_edges = x.shape
    if n == 0:
        raise ProblemError("exact_episode_optimum needs at least one world")
    if n > MAX_EPISODE_WORLDS:
        raise ProblemError(
            f"exact_episode_optimum is exponential in the number of worlds: {n} > {MAX_EPISODE_WORLDS}"
        )
    costs = _costs(edge_costs, num_edges)
    weights = _prior(prior, n)
    library = _library(paths, num_edges)
    edges, path_masks = _local_path_masks(library)
    keep = weights > 0
    x, weights = x[keep], weights[keep]
    mass = _Mass(weights)
    local_x = x[:, edges]
    world_masks = _column_masks(local_x)  # per local edge: worlds where it is free
    free_bits = [sum(1 << j for j in np.flatnonzero(row).tolist()) for row in local_x]  # per world
    local_costs = [float(costs[e]) for e in edges]
    memo: dict[tuple[int, int, int], float] = {}

    def value(checked: int, h: int) -> float:
        rep = (h & -h).bit_length() - 1  # any world of H': they agree on the checked edges
        free = checked & free_bits[rep]
        blocked = checked & ~free_bits[rep]
        union = 0
        alive = 0
        for i, pm in enumerate(path_masks):
            if pm & blocked == 0:
                if pm & free == pm:
                    return 0.0
                union |= pm
                alive |= 1 << i
        if union == 0:
            return 0.0
        # Checks off the alive paths no longer matter (the alive set is part of the key).
        key = (alive, checked & union, h)
        cached = memo.get(key)
        if cached is not None:
            return cached
        ph = mass(h)
        best = math.inf
        for j in sorted(_bits(union & ~checked), key=local_costs.__getitem__):
            c = local_costs[j]
            if c >= best:
                break
            nxt = checked | (1 << j)
            h1 = h & world_masks[j]
            h0 = h ^ h1
            if h0 == 0 or h1 == 0:
                v = c + value(nxt, h)
            else:
                p1 = mass(h1) / ph
                v = c + p1 * value(nxt, h1)
                if v < best:
                    v += (1.0 - p1) * value(nxt, h0)
            best = min(best, v)
        memo[key] = best
        return best

    return float(value(0, (1 << x.shape[0]) - 1))


# --------------------------------------------------------------------------------------------------
# 8.2 independent-edge (SBFE) optimum
# --------------------------------------------------------------------------------------------------


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
    th = _theta(theta)
    costs = _costs(edge_costs, th.size)
    library = _library(paths, th.size)
    edges, path_masks = _local_path_masks(library)
    local_theta = [float(th[e]) for e in edges]
    local_costs = [float(costs[e]) for e in edges]
    order = sorted(range(len(edges)), key=local_costs.__getitem__)
    memo: dict[tuple[int, int, int], float] = {}

    def value(alive: int, known: int, free: int) -> float:
        """alive: bitmask of path ids; known/free: bitmasks of local edges (free within known)."""
        union = 0
        for i in _bits(alive):
            pm = path_masks[i]
            if pm & free == pm:
                return 0.0
            union |= pm
        if union == 0:
            return 0.0
        known &= union
        free &= union
        key = (alive, known, free)
        cached = memo.get(key)
        if cached is not None:
            return cached
        best = math.inf
        unknown = union & ~known
        for j in order:
            bit = 1 << j
            if not unknown & bit:
                continue
            c = local_costs[j]
            if c >= best:
                break
            q = local_theta[j]
            v = c
            if q > 0.0:
                v += q * value(alive, known | bit, free | bit)
            if q < 1.0 and v < best:
                dead = sum(1 << i for i in _bits(alive) if path_masks[i] & bit)
                v += (1.0 - q) * value(alive & ~dead, known | bit, free)
            best = min(best, v)
        memo[key] = best
        return best

    return float(value((1 << len(path_masks)) - 1, 0, 0))


# --------------------------------------------------------------------------------------------------
# expected cost of a given policy
# --------------------------------------------------------------------------------------------------


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
    th = _theta(theta)
    costs = _costs(edge_costs, th.size)
    library = _library(paths, th.size)
    path_sets = [[int(e) for e in p] for p in library.path_edges]
    visited = 0

    def determined(obs: Mapping[int, bool]) -> bool:
        all_blocked = True
        for p in path_sets:
            outcomes = [obs.get(e) for e in p]
            if False in outcomes:
                continue
            if None not in outcomes:
                return True  # every edge checked free
            all_blocked = False
        return all_blocked

    def value(obs: dict[int, bool]) -> float:
        nonlocal visited
        visited += 1
        if visited > max_nodes:
            raise ProblemError(f"the policy's decision tree has more than {max_nodes} nodes")
        if determined(obs):
            return 0.0
        choice = make_selector(dict(obs)).select()
        if choice is None:
            return 0.0
        e = int(choice)
        if not 0 <= e < th.size:
            raise PolicyError(f"the policy chose edge {e}, outside [0, {th.size})")
        if e in obs:
            raise PolicyError(f"the policy chose edge {e} a second time")
        q = float(th[e])
        v = float(costs[e])
        if q > 0.0:
            v += q * value({**obs, e: True})
        if q < 1.0:
            v += (1.0 - q) * value({**obs, e: False})
        return v

    return float(value({}))


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
    x = _bool_matrix("X", X)
    n, num_edges = x.shape
    if n == 0:
        raise ProblemError("expected_policy_cost_database needs at least one world")
    _costs(edge_costs, num_edges)
    _path_library(paths, num_edges)
    weights = _prior(prior, n)
    total = 0.0
    for h in np.flatnonzero(weights > 0).tolist():
        cost = float(run_one(h))
        if not math.isfinite(cost) or cost < 0:
            raise ProblemError(f"run_one({h}) returned {cost}; costs must be finite and >= 0")
        total += float(weights[h]) * cost
    return total / float(weights.sum())
