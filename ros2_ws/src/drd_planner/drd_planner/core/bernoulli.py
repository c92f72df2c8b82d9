"""The Bernoulli library state shared by BiSECt and the Bernoulli baselines (ALGORITHMS.md 2.1, 2.5).

Edges are independent, x_e ~ Bernoulli(theta_e). For each path i the state keeps log p_i, the log
probability that its untested edges are all free (observed edges are clamped to their outcome), whether
it is alive (no observed blocked edge), how many of its edges are still untested, and for each edge
how many alive paths pass through it. An observation costs O(number of paths through the edge).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.library import PathLibrary
from drd_planner.core.region_rule import ProofOrder, region_scores
from drd_planner.exceptions import ProblemError

#: theta is clamped into [THETA_EPS, 1 - THETA_EPS] so that no untested path has p = 1 or 0.
THETA_EPS = 1e-9


class BernoulliLibraryState:
    """Clamped bias and per-path log p_i for one episode.

    Args:
        library: the m paths.
        theta: (E,) bias, P(edge free), in [0, 1] (clamped into (0, 1) internally).
        observations: edges already checked (edge -> free), clamped before the first selection.
    """

    def __init__(
        self,
        library: PathLibrary,
        theta: npt.ArrayLike,
        *,
        observations: Mapping[int, bool] | None = None,
    ) -> None:
        th = np.asarray(theta, dtype=np.float64).ravel()
        if th.shape != (library.num_edges,) or not np.all((th >= 0) & (th <= 1)):
            raise ProblemError(f"theta must be ({library.num_edges},) values in [0, 1]")
        th = np.clip(th, THETA_EPS, 1.0 - THETA_EPS)
        self._library = library
        self._csc = library.incidence_csc
        self._csr = library.incidence
        self._theta = th
        self._log_theta = np.log(th)
        self._log_1m_theta = np.log1p(-th)
        self._proof_order: ProofOrder | None = None
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

    def most_probable_path(self) -> int:
        """i* = argmax over alive paths of p_i (first index on ties): the MaxProbReg path."""
        return int(np.argmax(np.where(self._alive, self._logp, -np.inf)))

    def region_path(self, rule: str, edge_costs: FloatArray) -> int:
        """The alive path the region rule ``rule`` picks (:mod:`drd_planner.core.region_rule`).

        ``"probability"`` is :meth:`most_probable_path`; ``"per_check"`` ranks by p_i per expected check.
        """
        if rule == "probability":
            return self.most_probable_path()
        if self._proof_order is None:  # sorted once per bias
            self._proof_order = ProofOrder(self._csr.indptr, self._csr.indices, self._theta, edge_costs)
        costs = self._proof_order.costs(self._tested, self._alive)
        return int(np.argmax(region_scores(rule, self.log_path_probability, costs)))

    def untested_edges_of(self, path: int) -> IntArray:
        """Sorted untested edges of ``path``."""
        row = self._csr.indices[self._csr.indptr[path] : self._csr.indptr[path + 1]]
        return np.asarray(row[~self._tested[row]], dtype=np.int64)

    def alive_candidates(self) -> IntArray:
        """Sorted untested edges that lie on at least one alive path."""
        return np.flatnonzero((self._alive_through > 0) & ~self._tested).astype(np.int64)

    def alive_incidence(self, candidates: IntArray) -> tuple[IntArray, IntArray]:
        """The alive paths through each candidate, flattened.

        Returns:
            seg: index into ``candidates`` of each entry (non-decreasing).
            paths: the alive path of each entry (increasing within a candidate).
        """
        cand = np.asarray(candidates, dtype=np.int64)
        starts = self._csc.indptr[cand]
        lengths = self._csc.indptr[cand + 1] - starts
        seg = np.repeat(np.arange(cand.size), lengths)
        offsets = np.arange(seg.size) - np.repeat(np.cumsum(lengths) - lengths, lengths)
        paths = self._csc.indices[np.repeat(starts, lengths) + offsets].astype(np.int64)
        keep = self._alive[paths]
        return seg[keep], paths[keep]

    def set_theta(self, theta: npt.ArrayLike) -> None:
        """Replace the bias of the untested edges and recompute every path's log p_i.

        Observed edges stay clamped to their outcome; dead paths stay dead.
        """
        th = np.asarray(theta, dtype=np.float64).ravel()
        if th.shape != self._theta.shape or not np.all((th >= 0) & (th <= 1)):
            raise ProblemError(f"theta must be ({self._theta.size},) values in [0, 1]")
        th = np.clip(th, THETA_EPS, 1.0 - THETA_EPS)
        self._theta = th
        self._log_theta = np.log(th)
        self._log_1m_theta = np.log1p(-th)
        self._proof_order = None
        self._logp = np.asarray(self._csr @ np.where(self._tested, 0.0, self._log_theta), dtype=np.float64)

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
