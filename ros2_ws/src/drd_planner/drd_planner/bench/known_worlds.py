"""A lower bound on every policy's mean checks that counts search, not only verification.

The oracle bound (:func:`~drd_planner.core.bounds.oracle_lower_bound`) charges each world only the
cheapest valid library path: it is what a policy told the world would pay. A policy that is only told
that the world is *one of* a group ``G`` of known worlds must still find out which, and its checks
that find out are paid too. The optimal expected cost of that game, ``OPT(G)``, is a lower bound on
the mean cost over ``G`` of *any* policy (any policy is a policy for the game), and for any partition
of a set of worlds into groups ``G_i``,

    OPT(G) >= sum_i |G_i| / |G| OPT(G_i)

(the optimal policy for ``G``, run on the worlds of ``G_i``, is a policy for ``G_i``). So the mean of
``OPT`` over a partition of the test worlds into groups bounds every policy's mean over them from
below, for groups of one it is the oracle bound, and it grows with the group size towards ``OPT`` of
all the test worlds (and, over random groups drawn from the world distribution, towards the
Bayes-optimal policy's expected cost).

``OPT(G)`` is exponential in ``|G|`` (docs/algorithms.md, "Bounds and exact optima");
:func:`known_worlds_optimum` solves it exactly by depth-first branch and bound with the oracle bound as the
admissible heuristic, using three facts that keep groups of ~20 worlds tractable on the authors' graphs:

* *informative checks first*: a check whose outcome is the same in every world still possible can be
  moved to the end of its branch at no cost (its outcome is known), so an optimal policy makes only
  informative checks, then checks the remaining edges of one library path valid in every world left;
* *memo on what matters*: the value depends on the worlds left ``H`` and on the checked edges that lie
  on library paths valid in some world of ``H``;
* *dominance*: of two checks that split ``H`` the same way, one that costs no more and lies on every
  relevant path the other lies on is never worse.

Worlds without a valid library path are refused (their certificate is a cut, not a path); so are
groups whose search passes the node budget (a :class:`~drd_planner.exceptions.ProblemError`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.bench.optima_support import PathsLike, bits, check_costs, path_library
from drd_planner.core.bounds import bool_matrix
from drd_planner.core.library import PathLibrary
from drd_planner.exceptions import ProblemError

__all__ = ["DEFAULT_NODE_BUDGET", "KnownWorldsBound", "known_worlds_bound", "known_worlds_optimum"]

#: Search nodes one group may expand before the solver gives up (a ProblemError).
DEFAULT_NODE_BUDGET = 200_000
_EPS = 1e-9


class _Solver:
    """Branch and bound over (worlds left H as a bitmask, checked candidate edges as a bitmask)."""

    def __init__(self, x: BoolArray, library: PathLibrary, costs: FloatArray, node_budget: int) -> None:
        """(g, E) outcomes ``x`` of the group's worlds, the library, (E,) check costs."""
        valid = library.valid_paths(x)  # (g, m)
        if not valid.any(axis=1).all():
            bad = np.flatnonzero(~valid.any(axis=1)).tolist()
            raise ProblemError(f"worlds {bad} of the group have no valid library path")
        relevant = np.flatnonzero(valid.any(axis=0))
        self.valid = valid[:, relevant]  # (g, r) over the paths valid in some world of the group
        incidence = library.dense_incidence()[relevant]  # (r, E)
        on_path = np.flatnonzero(incidence.any(axis=0))
        # Off-path edges only inform: keep the cheapest per distinct outcome column.
        cheapest: dict[bytes, int] = {}
        for e in np.flatnonzero(~incidence.any(axis=0)).tolist():
            key = np.packbits(x[:, e]).tobytes()
            if key not in cheapest or costs[e] < costs[cheapest[key]]:
                cheapest[key] = e
        self.edges: IntArray = np.concatenate([on_path, np.array(sorted(cheapest.values()), dtype=np.int64)])
        self.cost: FloatArray = costs[self.edges]
        self.on: BoolArray = incidence[:, self.edges]  # (r, K)
        self.weighted: FloatArray = self.on * self.cost[None, :]  # (r, K) cost credited per check
        self.free: BoolArray = x[:, self.edges]  # (g, K)
        self.path_cost: FloatArray = self.weighted.sum(axis=1)  # (r,)
        self.world_edges = [  # per world: bitmask of the candidates on its valid paths
            _mask(np.flatnonzero(self.on[self.valid[w]].any(axis=0))) for w in range(x.shape[0])
        ]
        self.memo: dict[tuple[int, int], tuple[float, bool]] = {}
        self.nodes = 0
        self.node_budget = node_budget

    def _key(self, h: int, worlds: list[int], checked: int) -> tuple[int, int]:
        """Memo key: the worlds left and the checks on library paths valid in one of them."""
        edges = 0
        for w in worlds:
            edges |= self.world_edges[w]
        return h, checked & edges

    def _count_node(self) -> None:
        self.nodes += 1
        if self.nodes > self.node_budget:
            raise ProblemError(
                f"the known-worlds search passed its budget of {self.node_budget} nodes; "
                "use smaller groups or a larger node budget"
            )

    def solve(self, h: int, checked: int, remaining: FloatArray, bound: float) -> float:
        """The optimal expected cost from state (h, checked) if below ``bound``; else a lower bound >= it.

        ``remaining`` is (r,) each path's cost of its unchecked edges.
        """
        worlds = bits(h)
        key = self._key(h, worlds, checked)
        hit = self.memo.get(key)
        if hit is not None and (hit[1] or hit[0] >= bound):
            return hit[0]
        self._count_node()
        valid = self.valid[worlds]  # (n, r)
        rows = np.flatnonzero(valid.any(axis=0))
        valid, rem = valid[:, rows], remaining[rows]
        lower = float(np.where(valid, rem[None, :], np.inf).min(axis=1).mean())  # mean oracle given the checks
        common = valid.all(axis=0)
        finish = float(rem[common].min()) if common.any() else math.inf
        if len(worlds) == 1 or finish <= lower + _EPS:
            self.memo[key] = (finish, True)
            return finish
        best, exact = (finish, True) if finish < bound else (bound, False)
        if lower < best - _EPS:
            value = self._branch(_Node(h, worlds, checked, remaining, rows, valid, rem), best)
            if value < best - _EPS:
                best, exact = value, True
        elif not exact:
            best = max(lower, bound)
        self.memo[key] = (best, exact)
        return best

    def _branch(self, node: _Node, best: float) -> float:
        """The best informative check's expected cost if below ``best``, else ``best``."""
        free = self.free[node.worlds]  # (n, K)
        cand = np.flatnonzero(free.any(axis=0) & ~free.all(axis=0))
        credit = self.weighted[node.rows][:, cand]  # (r', k)
        # (n, k) each world's oracle after each check; cost + their mean is admissible.
        after = np.stack([(node.rem[v, None] - credit[v]).min(axis=0) for v in node.valid])
        estimates = self.cost[cand] + after.mean(axis=0)
        n = len(node.worlds)
        tried: dict[bytes, list[tuple[int, float]]] = {}  # split -> (paths, cost) of the checks tried
        for j in np.argsort(estimates, kind="stable").tolist():
            if estimates[j] >= best - _EPS:
                break
            e = int(cand[j])
            outcome = free[:, e]
            split, paths, c = (
                outcome.tobytes(),
                _mask(np.flatnonzero(self.on[node.rows, e])),
                float(self.cost[e]),
            )
            if any(paths & ~p == 0 and cp <= c for p, cp in tried.get(split, ())):
                continue  # dominated: a check tried already splits the same way, costs no more, covers its paths
            tried.setdefault(split, []).append((paths, c))
            n1 = int(outcome.sum())
            h1 = sum(1 << w for w, f in zip(node.worlds, outcome.tolist(), strict=True) if f)
            low0 = float(after[~outcome, j].mean())
            child = node.remaining - self.weighted[:, e]
            checked = node.checked | 1 << e
            v1 = self.solve(h1, checked, child, (best - c - (n - n1) / n * low0) * n / n1)
            if c + n1 / n * v1 + (n - n1) / n * low0 >= best - _EPS:
                continue
            v0 = self.solve(node.h & ~h1, checked, child, (best - c - n1 / n * v1) * n / (n - n1))
            best = min(best, c + n1 / n * v1 + (n - n1) / n * v0)
        return best


class _Node(NamedTuple):
    """One search state with its worlds' relevant paths (rows) and their unchecked costs."""

    h: int
    worlds: list[int]
    checked: int
    remaining: FloatArray  # (r,) over every relevant path of the group
    rows: IntArray  # the paths valid in some world of h
    valid: BoolArray  # (n, r') validity of those paths per world of h
    rem: FloatArray  # (r',) their unchecked costs


def _mask(indices: npt.ArrayLike) -> int:
    """Bitmask with the given bit indices set."""
    out = 0
    for i in np.asarray(indices, dtype=np.int64).tolist():
        out |= 1 << i
    return out


def known_worlds_optimum(
    X: npt.ArrayLike,
    paths: PathsLike | PathLibrary,
    edge_costs: npt.ArrayLike,
    *,
    node_budget: int = DEFAULT_NODE_BUDGET,
) -> float:
    """Optimal expected checks to prove a library path free when the world is one of ``X``'s rows.

    The prior is uniform over the rows. Any policy's mean cost over these worlds is at least this;
    it equals :func:`~drd_planner.bench.optima.exact_episode_optimum` when every edge is a library
    edge, and it is at least the mean oracle bound.

    Args:
        X: (g, E) bool edge outcomes of the known worlds; each must have a valid library path.
        paths: the library (m paths of edge ids in [0, E), or a PathLibrary).
        edge_costs: (E,) positive check costs.
        node_budget: search nodes allowed before a ProblemError.

    Returns:
        The optimal expected cost (same unit as ``edge_costs``).
    """
    x = bool_matrix("X", X)
    if x.shape[0] == 0:
        raise ProblemError("known_worlds_optimum needs at least one world")
    library = paths if isinstance(paths, PathLibrary) else path_library(paths, x.shape[1])
    if library.num_edges != x.shape[1]:
        raise ProblemError(f"the library spans {library.num_edges} edges, X has {x.shape[1]} columns")
    costs = check_costs(edge_costs, x.shape[1])
    solver = _Solver(x, library, costs, node_budget)
    return solver.solve((1 << x.shape[0]) - 1, 0, solver.path_cost.copy(), math.inf)


@dataclass(frozen=True)
class KnownWorldsBound:
    """The partition bound over one set of worlds.

    Attributes:
        group_size: the largest group size asked for.
        groups: per group the world ids (rows of the caller's X) it holds.
        optima: (len(groups),) OPT of each group.
        oracle: (len(groups),) the mean oracle bound of each group.
    """

    group_size: int
    groups: tuple[tuple[int, ...], ...]
    optima: FloatArray
    oracle: FloatArray

    @property
    def sizes(self) -> IntArray:
        """(len(groups),) worlds per group."""
        return np.array([len(g) for g in self.groups], dtype=np.int64)

    @property
    def mean(self) -> float:
        """The bound: the world-weighted mean of the groups' optima."""
        return float(np.average(self.optima, weights=self.sizes))

    @property
    def oracle_mean(self) -> float:
        """The oracle bound over the same worlds."""
        return float(np.average(self.oracle, weights=self.sizes))


def known_worlds_bound(
    X: npt.ArrayLike,
    paths: PathsLike | PathLibrary,
    edge_costs: npt.ArrayLike,
    world_ids: npt.ArrayLike,
    *,
    group_size: int,
    seed: int = 0,
    node_budget: int = DEFAULT_NODE_BUDGET,
) -> KnownWorldsBound:
    """Split ``world_ids`` into groups of at most ``group_size`` (seeded shuffle) and solve each group.

    The returned mean bounds from below the mean cost over ``world_ids`` of every policy that proves
    a library path free (see the module docstring).

    Args:
        X: (n, E) bool edge outcomes of all worlds.
        paths: the library.
        edge_costs: (E,) positive check costs.
        world_ids: the worlds to bound (e.g. the test worlds), each with a valid library path.
        group_size: largest group (>= 1); sizes differ by at most one.
        seed: the shuffle's seed.
        node_budget: per group, as in :func:`known_worlds_optimum`.
    """
    if group_size < 1:
        raise ProblemError(f"group_size must be >= 1, got {group_size}")
    x = bool_matrix("X", X)
    ids = np.asarray(world_ids, dtype=np.int64).ravel()
    if ids.size == 0 or ids.min() < 0 or ids.max() >= x.shape[0]:
        raise ProblemError(f"world_ids must be non-empty ids in [0, {x.shape[0]})")
    library = paths if isinstance(paths, PathLibrary) else path_library(paths, x.shape[1])
    costs = check_costs(edge_costs, x.shape[1])
    order = np.random.default_rng(seed).permutation(ids)
    parts = np.array_split(order, math.ceil(ids.size / group_size))
    path_costs = library.path_costs(costs)
    valid = library.valid_paths(x[ids])
    oracle_of = dict(zip(ids.tolist(), np.where(valid, path_costs, np.inf).min(axis=1).tolist(), strict=True))
    optima, oracle = [], []
    for part in parts:
        optima.append(known_worlds_optimum(x[part], library, costs, node_budget=node_budget))
        oracle.append(float(np.mean([oracle_of[w] for w in part.tolist()])))
    return KnownWorldsBound(
        group_size=group_size,
        groups=tuple(tuple(int(w) for w in p) for p in parts),
        optima=np.array(optima),
        oracle=np.array(oracle),
    )
