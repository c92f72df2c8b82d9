"""BiSECt: Bernoulli subregion edge cutting over a path library (ALGORITHMS.md section 2).

Edges are independent, x_e ~ Bernoulli(theta_e). For each alive path i we keep log p_i, the log
probability that its untested edges are all free (observed edges are clamped to their outcome).
The gain of testing edge e is the closed form of section 2.3, evaluated in log space and
vectorised over all candidate edges at once.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import numpy.typing as npt

from drd_planner.core.library import PathLibrary
from drd_planner.core.logmath import log1mexp
from drd_planner.exceptions import ProblemError

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]

#: theta is clamped into [THETA_EPS, 1 - THETA_EPS] so that no untested path has p = 1 or 0.
THETA_EPS = 1e-9


def bias_from_worlds(
    X: npt.ArrayLike, weights: npt.ArrayLike | None = None, *, alpha: float = 0.99
) -> FloatArray:
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
    w = np.ones(xa.shape[0]) if weights is None else np.asarray(weights, dtype=np.float64)
    total = w.sum()
    if total <= 0:
        return np.full(xa.shape[1], 0.5)
    mean = (w @ xa.astype(np.float64)) / total
    return np.asarray(alpha * mean + (1.0 - alpha) * 0.5, dtype=np.float64)


class Bisect:
    """The BiSECt selection state for one episode.

    Args:
        library: the m paths.
        theta: (E,) bias, P(edge free), in (0, 1).
        edge_costs: (E,) positive check costs.
        max_prob_region: restrict candidates to the most probable alive path (MaxProbReg, option 1).
        lite: use the un-squared outcome factor (BiSECt-lite, exponent n_e + 1 instead of 2 n_e + 1).
        observations: edges already checked (edge -> free), clamped before the first selection.
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
    ) -> None:
        th = np.asarray(theta, dtype=np.float64).ravel()
        if th.shape != (library.num_edges,) or not np.all((th >= 0) & (th <= 1)):
            raise ProblemError(f"theta must be ({library.num_edges},) values in [0, 1]")
        th = np.clip(th, THETA_EPS, 1.0 - THETA_EPS)
        self._library = library
        self._csc = library.incidence_csc
        self._csr = library.incidence
        self._log_theta = np.log(th)
        self._log_1m_theta = np.log1p(-th)
        self._costs = np.asarray(edge_costs, dtype=np.float64)
        self._max_prob_region = max_prob_region
        self._exponent_factor = 1 if lite else 2
        self._tested = np.zeros(library.num_edges, dtype=bool)
        self._alive = np.ones(library.num_paths, dtype=bool)
        self._remaining = np.diff(self._csr.indptr).astype(np.int64)
        self._logp = np.asarray(self._csr @ self._log_theta, dtype=np.float64)
        self._alive_through = np.diff(self._csc.indptr).astype(np.int64)
        for edge, free in (observations or {}).items():
            self.observe(edge, free)

    @property
    def alive(self) -> BoolArray:
        """(m,) paths with no observed blocked edge (a copy)."""
        return np.array(self._alive, dtype=bool)

    @property
    def log_path_probability(self) -> FloatArray:
        """(m,) log p_i; -inf for dead paths (a copy)."""
        return np.where(self._alive, self._logp, -np.inf)

    def solved(self) -> bool:
        """True when some path is proven free or every path is dead."""
        return not self._alive.any() or bool(np.any(self._alive & (self._remaining == 0)))

    def gains(self, candidates: IntArray) -> FloatArray:
        """Normalised expected gain g(e) / c(e) for each candidate edge (ALGORITHMS.md 2.3)."""
        cand = np.asarray(candidates, dtype=np.int64)
        starts = self._csc.indptr[cand]
        ends = self._csc.indptr[cand + 1]
        lengths = ends - starts
        seg = np.repeat(np.arange(cand.size), lengths)
        offsets = np.arange(seg.size) - np.repeat(np.cumsum(lengths) - lengths, lengths)
        paths = self._csc.indices[np.repeat(starts, lengths) + offsets]
        keep = self._alive[paths]
        seg, paths = seg[keep], paths[keep]
        n = np.bincount(seg, minlength=cand.size).astype(np.float64)
        logp = self._logp[paths]
        lq = self._log_theta[cand]
        l1q = self._log_1m_theta[cand]
        log_blocked = log1mexp(logp)  # log(1 - p_i)
        # log(1 - p_i / theta_e); exactly -inf when e is the path's last untested edge.
        last = self._remaining[paths] == 1
        log_rest = np.where(last, -np.inf, log1mexp(np.minimum(logp - lq[seg], 0.0)))
        sum_blocked = np.bincount(seg, weights=log_blocked, minlength=cand.size)
        rest_neg_inf = np.bincount(seg, weights=np.isneginf(log_rest), minlength=cand.size) > 0
        sum_rest = np.bincount(
            seg, weights=np.where(np.isneginf(log_rest), 0.0, log_rest), minlength=cand.size
        )
        sum_rest[rest_neg_inf] = -np.inf
        k = self._exponent_factor * n + 1.0
        l1 = k * lq + sum_rest - sum_blocked
        l0 = k * l1q - sum_blocked
        gain = -np.expm1(np.logaddexp(l1, l0))
        return np.asarray(gain / self._costs[cand], dtype=np.float64)

    def most_probable_path(self) -> int:
        """i* = argmax over alive paths of p_i (first index on ties)."""
        return int(np.argmax(np.where(self._alive, self._logp, -np.inf)))

    def _untested_edges_of(self, path: int) -> IntArray:
        row = self._csr.indices[self._csr.indptr[path] : self._csr.indptr[path + 1]]
        return np.asarray(row[~self._tested[row]], dtype=np.int64)

    def select(self) -> int | None:
        """The next edge to check, or None when solved."""
        if self.solved():
            return None
        istar = self.most_probable_path()
        own = self._untested_edges_of(istar)
        own_gain = self.gains(own)
        e_own = int(own[int(np.argmax(own_gain))])
        if self._max_prob_region:
            return e_own
        cand = np.flatnonzero((self._alive_through > 0) & ~self._tested)
        gain = self.gains(cand)
        best = int(np.argmax(gain))
        # Tie-break of the authors' code: prefer i*'s best edge when its gain equals the best.
        return e_own if own_gain.max() == gain[best] else int(cand[best])

    def observe(self, edge: int, free: bool) -> None:
        """Clamp ``edge`` to its outcome and update the paths through it."""
        if self._tested[edge]:
            return
        self._tested[edge] = True
        paths = self._csc.indices[self._csc.indptr[edge] : self._csc.indptr[edge + 1]]
        if free:
            self._logp[paths] -= self._log_theta[edge]
            self._remaining[paths] -= 1
            self._logp[paths[self._remaining[paths] == 0]] = 0.0
        else:
            dying = paths[self._alive[paths]]
            self._alive[dying] = False
            for p in dying.tolist():
                row = self._csr.indices[self._csr.indptr[p] : self._csr.indptr[p + 1]]
                self._alive_through[row] -= 1
