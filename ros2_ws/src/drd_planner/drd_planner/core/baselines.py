"""Bernoulli baselines on the path library (docs/algorithms.md, "The Bernoulli baselines").

All of them share BiSECt's state (:class:`BernoulliLibraryState`): the training-set bias theta
(clamped, never updated) and log p_i per path with observed edges clamped. They stop (``select``
returns None) when some path is proven free or none is alive. "MaxProbReg" (option 1) restricts the
candidates to the untested edges of i* = argmax_{alive} p_i (first index on ties); option 0 uses
every candidate. Each rule follows the authors' MATLAB function named in its docstring, including
its tie-breaking: first maximum in increasing edge id, or uniformly at random where the authors drew
at random (seeded here).
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.core.bernoulli import BernoulliLibraryState
from drd_planner.core.library import PathLibrary
from drd_planner.exceptions import ProblemError

#: Scores within this absolute distance in log space (a relative 1e-12 in probability) are ties, so
#: that rounding in a sum of logs cannot decide between mathematically equal probabilities.
LOG_TIE_TOL = 1e-12


def first_max(values: npt.ArrayLike, tol: float = 0.0) -> int:
    """Index of the first value within ``tol`` of the maximum (the first index when all are -inf)."""
    v = np.asarray(values, dtype=np.float64)
    best = v.max()
    if not np.isfinite(best):
        return int(np.argmax(v == best))
    return int(np.argmax(v >= best - tol))


def random_max(values: npt.ArrayLike, rng: np.random.Generator, tol: float = 0.0) -> int:
    """A uniformly random index among the values within ``tol`` of the maximum."""
    v = np.asarray(values, dtype=np.float64)
    best = v.max()
    ties = np.flatnonzero(v == best) if not np.isfinite(best) else np.flatnonzero(v >= best - tol)
    return int(ties[int(rng.integers(ties.size))])


def segment_logsumexp(values: FloatArray, seg: IntArray, num_segments: int) -> FloatArray:
    """Log-sum-exp of ``values`` grouped by ``seg``; -inf for empty segments."""
    out = np.full(num_segments, -np.inf)
    if seg.size == 0:
        return out
    top = np.full(num_segments, -np.inf)
    np.maximum.at(top, seg, values)
    shift = np.where(np.isfinite(top), top, 0.0)
    sums = np.bincount(seg, weights=np.exp(values - shift[seg]), minlength=num_segments)
    has = sums > 0
    out[has] = shift[has] + np.log(sums[has])
    return out


class BernoulliBaseline(BernoulliLibraryState, ABC):
    """A Bernoulli baseline as a :class:`drd_planner.core.episode.Policy` (name, stage, select, observe).

    Subclasses implement :meth:`choose`, called only while the episode is unsolved.

    Args:
        library: the m paths.
        theta: (E,) training-set bias P(edge free).
        name: registry name (also the stage label of every check).
        max_prob_region: MaxProbReg restriction (option 1) instead of all candidates (option 0).
        seed: seed of the tie-breaking / sampling generator.
    """

    def __init__(
        self,
        library: PathLibrary,
        theta: npt.ArrayLike,
        *,
        name: str,
        max_prob_region: bool = True,
        seed: int = 0,
    ) -> None:
        super().__init__(library, theta)
        self._name = name
        self._max_prob_region = max_prob_region
        self._rng = np.random.default_rng(seed)

    @property
    def name(self) -> str:
        """Registry name."""
        return self._name

    @property
    def stage(self) -> str:
        """The policy name: a baseline has one stage."""
        return self._name

    def select(self) -> int | None:
        """The next edge, or None when some path is proven free or none is alive."""
        if self.solved():
            return None
        return self.choose()

    @abstractmethod
    def choose(self) -> int:
        """The next edge of an unsolved episode."""

    def restricted_candidates(self) -> IntArray:
        """Untested edges of i* under MaxProbReg, else untested edges on any alive path (sorted)."""
        if self._max_prob_region:
            return self.untested_edges_of(self.most_probable_path())
        return self.alive_candidates()

    def untested_library_edges(self) -> IntArray:
        """Untested edges on any library path, dead ones included (the authors' option-0 candidates)."""
        return np.flatnonzero((np.diff(self._csc.indptr) > 0) & ~self._tested).astype(np.int64)


class MaxTally(BernoulliBaseline):
    """MaxTally (``max_tally_test.m``): the edge on the most paths; ties uniformly at random.

    Option 1 counts alive paths over the untested edges of i*. Option 0 counts *all* paths (dead ones
    included) over the untested edges of every path (even edges only on dead paths), as the authors do.
    """

    def choose(self) -> int:
        """Most-tallied candidate."""
        if self._max_prob_region:
            cand = self.restricted_candidates()
            tally = self._alive_through[cand]
        else:
            cand = self.untested_library_edges()
            tally = np.diff(self._csc.indptr)[cand]
        return int(cand[random_max(tally, self._rng)])


class WeightedMaxTally(BernoulliBaseline):
    """Probability-weighted MaxTally (``weighted_max_tally_test.m``): argmax of sum_{alive i ∋ e} p_i.

    Ties uniformly at random. Option 0's candidates are the untested edges of every path, but edges on
    dead paths only score 0 and an unsolved episode always has a positive-score edge, so this equals
    "untested edges on alive paths". Sums are taken in log space.
    """

    def choose(self) -> int:
        """Candidate with the largest probability-weighted tally."""
        cand = self.restricted_candidates()
        seg, paths = self.alive_incidence(cand)
        score = segment_logsumexp(self._logp[paths], seg, cand.size)
        return int(cand[random_max(score, self._rng, LOG_TIE_TOL)])


class RandomEdge(BernoulliBaseline):
    """Random (``rand_test.m``): a uniformly random candidate.

    Option 1 draws from the untested edges of i*; option 0 from the untested edges of any library
    path (dead ones included, as the authors do).
    """

    def choose(self) -> int:
        """Uniform random candidate."""
        cand = self.restricted_candidates() if self._max_prob_region else self.untested_library_edges()
        return int(cand[int(self._rng.integers(cand.size))])


class SetCover(BernoulliBaseline):
    """SetCover (``max_set_cover.m``): score(e) = theta_e + (1 - theta_e) * k_e, first maximum.

    k_e is the number of current candidates that would lie on no alive path if e were blocked, i.e.
    the candidates f whose alive paths all pass through e (e itself included). Under option 1 the
    candidate set is the untested edges of i*; under option 0 every untested edge on an alive path.
    """

    def choose(self) -> int:
        """Candidate with the best expected set-cover reduction."""
        cand = self.restricted_candidates()
        seg, paths = self.alive_incidence(cand)
        a = sp.csr_array((np.ones(seg.size), (paths, seg)), shape=(self._library.num_paths, cand.size))
        shared = (a.T @ a).tocoo()  # shared[f, t] = |P_f ∩ P_t| over alive paths
        size = self._alive_through[cand]
        covered = shared.data == size[shared.row]  # P_f ⊆ P_t
        k = np.bincount(shared.col[covered], minlength=cand.size).astype(np.float64)
        theta = self._theta[cand]
        score = theta + (1.0 - theta) * k
        return int(cand[first_max(score)])


class MVoI(BernoulliBaseline):
    """Myopic value of information (``max_mvoi.m``), with its built-in restriction.

    Candidates are the untested edges on *every* alive path achieving max p_i. score(e) =
    (1 - theta_e) * max_{alive i ∌ e} p_i (0 when every alive path uses e): the probability that e is
    blocked times the best path probability that survives it. First maximum in increasing edge id.
    """

    def __init__(self, library: PathLibrary, theta: npt.ArrayLike, *, name: str = "mvoi", seed: int = 0) -> None:
        super().__init__(library, theta, name=name, max_prob_region=True, seed=seed)

    def choose(self) -> int:
        """Candidate with the best P(blocked) x best surviving path probability."""
        logp = np.where(self._alive, self._logp, -np.inf)
        best = logp.max()
        top = np.flatnonzero(logp >= best - LOG_TIE_TOL)
        cand = np.unique(np.concatenate([self.untested_edges_of(int(i)) for i in top]))
        order = np.argsort(-logp, kind="stable")  # alive paths by decreasing p_i, ties by index
        order = order[self._alive[order]]
        rank = np.empty(self._library.num_paths, dtype=np.int64)
        rank[order] = np.arange(order.size)
        seg, paths = self.alive_incidence(cand)
        surviving = np.full(cand.size, -np.inf)
        for j in range(cand.size):
            through = np.sort(rank[paths[seg == j]])
            # The best path avoiding e is the first rank not taken by a path through e.
            gap = np.flatnonzero(through != np.arange(through.size))
            first_free = int(gap[0]) if gap.size else through.size
            if first_free < order.size:
                surviving[j] = logp[order[first_free]]
        score = self.edge_log_1m_theta(cand) + surviving
        return int(cand[first_max(score, LOG_TIE_TOL)])


class LazySPSet(BernoulliBaseline):
    """LazySP restricted to the library (``lazy_sp.m``, ``policyLazySP.m``).

    The candidate path is the alive library path of minimal geometric length (sum of graph edge
    lengths, independent of theta; first index on ties). Option 1 ("LazySP + MaxProbReg", ``weighted``)
    checks its untested edge with the largest sum of alive p_i through it (ties at random); option 0 a
    uniformly random untested edge of it.

    Args:
        path_lengths: (m,) geometric length of each library path.
        weighted: option 1 (True) or option 0 (False).
    """

    def __init__(
        self,
        library: PathLibrary,
        theta: npt.ArrayLike,
        path_lengths: npt.ArrayLike,
        *,
        weighted: bool = True,
        name: str | None = None,
        seed: int = 0,
    ) -> None:
        super().__init__(library, theta, name=name or ("lazysp_set" if weighted else "lazysp_set_random"), seed=seed)
        lengths = np.asarray(path_lengths, dtype=np.float64).ravel()
        if lengths.shape != (library.num_paths,):
            raise ProblemError(f"path lengths must have shape ({library.num_paths},), got {lengths.shape}")
        self._path_lengths = lengths
        self._weighted = weighted

    def shortest_alive_path(self) -> int:
        """The alive library path of minimal geometric length (first index on ties)."""
        return int(np.argmin(np.where(self._alive, self._path_lengths, np.inf)))

    def choose(self) -> int:
        """An untested edge of the shortest alive library path."""
        cand = self.untested_edges_of(self.shortest_alive_path())
        if not self._weighted:
            return int(cand[int(self._rng.integers(cand.size))])
        seg, paths = self.alive_incidence(cand)
        score = segment_logsumexp(self._logp[paths], seg, cand.size)
        return int(cand[random_max(score, self._rng, LOG_TIE_TOL)])
