"""BiSECt: Bernoulli subregion edge cutting over a path library (docs/algorithms.md, "BiSECt").

Edges are independent, x_e ~ Bernoulli(theta_e). The per-path state (log p_i of the untested edges,
observed edges clamped to their outcome) lives in :class:`BernoulliLibraryState`, shared with the
Bernoulli baselines. The gain of testing edge e is the closed form of section 2.3, evaluated in log
space and vectorised over all candidate edges at once.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.core.bernoulli import BernoulliLibraryState
from drd_planner.core.library import PathLibrary
from drd_planner.core.logmath import log1mexp, log1mexp_scalar, logaddexp_scalar
from drd_planner.core.region_rule import DEFAULT_REGION_RULE, check_region_rule

#: Up to this many (candidate, alive path) pairs the gains are summed in Python floats (``numpy``'s cost per
#: call dominates there); the same operations in the same order as the vectorised form, so the same numbers.
SCALAR_GAIN_PAIRS = 24
#: Worlds whose outcomes are turned into floats at a time by a weighted :func:`bias_from_worlds`.
_ROWS_PER_BLOCK = 64


def bias_from_worlds(X: npt.ArrayLike, weights: npt.ArrayLike | None = None, *, alpha: float = 0.99) -> FloatArray:
    """theta_e = alpha * (weighted) mean_h X[h, e] + (1 - alpha) * 0.5; 0.5 where no world is given.

    Args:
        X: (n, E) bool outcomes of the worlds the bias is learnt from.
        weights: (n,) non-negative prior weights, or None for uniform.
        alpha: weight of the data term (0.99 in the paper, i.e. mixing 0.01).

    Returns:
        (E,) float64 bias in [(1 - alpha) / 2, (1 + alpha) / 2].
    """
    xa = np.asarray(X, dtype=bool)
    if xa.shape[0] == 0:
        return np.full(xa.shape[1], 0.5)
    if weights is None:  # free counts straight from the booleans (no (n, E) float copy: 450 MB at real scale)
        mean = np.count_nonzero(xa, axis=0).astype(np.float64) / xa.shape[0]
        return np.asarray(alpha * mean + (1.0 - alpha) * 0.5, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    total = w.sum()
    if total <= 0:
        return np.full(xa.shape[1], 0.5)
    weighted = np.zeros(xa.shape[1])
    for lo in range(0, xa.shape[0], _ROWS_PER_BLOCK):  # a bounded float copy at a time
        weighted += w[lo : lo + _ROWS_PER_BLOCK] @ xa[lo : lo + _ROWS_PER_BLOCK].astype(np.float64)
    return np.asarray(alpha * (weighted / total) + (1.0 - alpha) * 0.5, dtype=np.float64)


class Bisect(BernoulliLibraryState):
    """The BiSECt selection state for one episode.

    Args:
        library: the m paths.
        theta: (E,) bias, P(edge free), in (0, 1).
        edge_costs: (E,) positive check costs.
        max_prob_region: restrict candidates to the edges of one alive path (MaxProbReg, option 1).
        lite: use the un-squared outcome factor (BiSECt-lite, exponent n_e + 1 instead of 2 n_e + 1).
        observations: edges already checked (edge -> free), clamped before the first selection.
        region_rule: which path ``max_prob_region`` restricts to (:data:`~drd_planner.core.region_rule.REGION_RULES`):
            the most probable (the paper's), or the most probable per expected check.
    """

    def __init__(
        self,
        library: PathLibrary,
        theta: npt.ArrayLike,
        edge_costs: npt.ArrayLike,
        *,
        max_prob_region: bool = True,
        lite: bool = False,
        observations: Mapping[int, bool] | None = None,
        region_rule: str = DEFAULT_REGION_RULE,
    ) -> None:
        self._costs = np.asarray(edge_costs, dtype=np.float64)
        self._max_prob_region = max_prob_region
        self._region_rule = check_region_rule(region_rule)
        self._exponent_factor = 1 if lite else 2
        super().__init__(library, theta, observations=observations)

    def gains(self, candidates: IntArray) -> FloatArray:
        """Normalised expected gain g(e) / c(e) for each candidate edge.

        The closed form: docs/algorithms.md, "The gain in closed form".
        """
        cand = np.asarray(candidates, dtype=np.int64)
        col = self._rows.column[cand]  # library-local index of each candidate
        n = self._alive_through[cand]  # alive paths through each candidate (the entries per segment)
        seg, paths = self._incidence(cand, n)
        size = paths.size
        # log p_i, then log(p_i / theta_e) capped at 0, side by side: one log(1 - e^x) for both.
        x = np.empty(2 * size)
        logp = np.take(self._logp, paths, out=x[:size])
        lq = self._lib_log_theta[col]
        np.subtract(logp, lq[seg], out=x[size:])
        np.minimum(x[size:], 0.0, out=x[size:])
        logs = log1mexp(x)
        log_blocked = logs[:size]  # log(1 - p_i)
        log_rest = logs[size:]  # log(1 - p_i / theta_e); exactly -inf when e is the path's last untested edge
        log_rest[self._remaining[paths] == 1] = -np.inf
        sum_blocked = np.bincount(seg, weights=log_blocked, minlength=cand.size)
        sum_rest = np.bincount(seg, weights=log_rest, minlength=cand.size)  # -inf where some term is
        k = self._exponent_factor * n + 1.0
        l1 = k * lq + sum_rest - sum_blocked
        l0 = k * self._lib_log_1m_theta[col] - sum_blocked
        gain = np.expm1(np.logaddexp(l1, l0))
        np.negative(gain, out=gain)
        return np.asarray(gain / self._costs[cand], dtype=np.float64)

    def scalar_gains(self, candidates: IntArray) -> list[float]:
        """:meth:`gains` term by term in Python floats, cheaper for a few candidates on a few alive paths.

        The same operations in the same order, so the same numbers where the scalar forms of
        :mod:`~drd_planner.core.logmath` equal ``numpy``'s elementwise ones.

        Args:
            candidates: (c,) edge ids.

        Returns:
            c floats, g(e) / c(e) of each candidate.
        """
        cand = np.asarray(candidates, dtype=np.int64)
        return self._scalar_gains(cand, self._alive_through[cand])

    def _scalar_gains(self, cand: IntArray, alive_counts: IntArray) -> list[float]:
        """:meth:`scalar_gains` of the (c,) int64 ``cand`` with their (c,) alive path counts."""
        col = self._rows.column[cand]
        counts = alive_counts.tolist()
        lqs = self._lib_log_theta[col].tolist()
        l1ms = self._lib_log_1m_theta[col].tolist()
        costs = self._costs[cand].tolist()
        through = [self._alive_paths_through(e) for e in cand.tolist()]
        paths = np.concatenate(through) if through else np.zeros(0, dtype=np.int64)
        logps = self._logp[paths].tolist()
        lasts = (self._remaining[paths] == 1).tolist()
        out = []
        at = 0
        for n, lq, l1m, cost in zip(counts, lqs, l1ms, costs, strict=True):
            sum_blocked = 0.0  # np.bincount adds each segment's terms one by one, from 0.0
            sum_rest = 0.0
            for lp, last in zip(logps[at : at + n], lasts[at : at + n], strict=True):
                sum_blocked += log1mexp_scalar(lp)
                sum_rest += -math.inf if last else log1mexp_scalar(min(lp - lq, 0.0))
            at += n
            k = self._exponent_factor * n + 1.0
            l1 = k * lq + sum_rest - sum_blocked
            l0 = k * l1m - sum_blocked
            out.append(-math.expm1(logaddexp_scalar(l1, l0)) / cost)
        return out

    def select(self) -> int | None:
        """The next edge to check, or None when solved."""
        if self.solved():
            return None
        istar = self.region_path(self._region_rule, self._costs)
        own = self.untested_edges_of(istar)
        counts = self._alive_through[own]
        if self._max_prob_region and int(counts.sum()) <= SCALAR_GAIN_PAIRS:
            listed = self._scalar_gains(own, counts)
            return int(own[max(range(len(listed)), key=listed.__getitem__)])  # the first best, as np.argmax
        own_gain = self.gains(own)
        e_own = int(own[int(np.argmax(own_gain))])
        if self._max_prob_region:
            return e_own
        cand = self.alive_candidates()
        gain = self.gains(cand)
        best = int(np.argmax(gain))
        # Tie-break of the authors' code: prefer i*'s best edge when its gain equals the best.
        return e_own if own_gain.max() == gain[best] else int(cand[best])
