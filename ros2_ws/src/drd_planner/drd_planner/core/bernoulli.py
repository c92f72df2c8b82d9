"""The Bernoulli library state shared by BiSECt and the Bernoulli baselines (docs/algorithms.md, "BiSECt").

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
from drd_planner.core.path_rows import column_sums, library_rows
from drd_planner.core.proof_order import ProofOrder
from drd_planner.core.region_rule import check_region_rule
from drd_planner.exceptions import ProblemError

#: theta is clamped into [THETA_EPS, 1 - THETA_EPS] so that no untested path has p = 1 or 0.
THETA_EPS = 1e-9


def _probabilities(values: FloatArray) -> bool:
    """True when every value lies in [0, 1] (NaN does not)."""
    return bool(values.min(initial=0.0) >= 0.0 and values.max(initial=1.0) <= 1.0)


class BernoulliLibraryState:
    """Clamped bias and per-path log p_i for one episode.

    An outcome updates only the paths through its edge: log p_i loses the edge's log theta (free), or
    the paths die (blocked). A new bias (:meth:`set_theta`, the posterior leaf) updates the bias of the
    edges whose value changed and makes log p_i of every path the sum of log theta over its untested
    edges again, as a state built from scratch holds it. The proof cost of the ``"per_check"`` region
    rule is kept the same way (:class:`~drd_planner.core.proof_order.ProofOrder`).

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
        if th.shape != (library.num_edges,) or not _probabilities(th):
            raise ProblemError(f"theta must be ({library.num_edges},) values in [0, 1]")
        self._library = library
        self._csc = library.incidence_csc
        self._csr = library.incidence
        self._rows = library_rows(library)
        k = self._rows.pad
        self._theta = np.minimum(np.maximum(th, THETA_EPS), 1.0 - THETA_EPS)
        # By library-local index (rows.column), plus the pad slot K (0 there): log theta, log(1 - theta), and
        # log theta while untested (0 once tested); whether each library edge is untested (False in the pad).
        self._lib_log_theta = np.zeros(k + 1)
        self._lib_log_1m_theta = np.zeros(k + 1)
        self._untested_log_theta = np.zeros(k + 1)
        self._lib_untested = np.ones(k + 1, dtype=bool)
        self._lib_untested[k] = False
        self._lib_theta = self._theta[self._rows.edges]  # (K,)
        self._library_logs()
        self._proof_order: ProofOrder | None = None
        self._tested = np.zeros(library.num_edges, dtype=bool)
        self._alive = np.ones(library.num_paths, dtype=bool)
        self._alive_ids = np.arange(library.num_paths, dtype=np.int64)  # flatnonzero(self._alive)
        self._num_alive = library.num_paths
        self._num_proven = 0  # alive paths with every edge checked free
        self._remaining = np.diff(self._csr.indptr).astype(np.int64)
        self._logp = self._path_sums()
        self._differenced = False  # some log p_i was updated by difference since the last sum
        self._alive_through = np.diff(self._csc.indptr).astype(np.int64)
        self._deaths = 0  # outcomes that killed some path so far
        self._through: dict[int, tuple[int, IntArray]] = {}  # edge -> (deaths then, its alive paths then)
        for edge, free in (observations or {}).items():
            self.observe(edge, free)

    def _library_logs(self) -> None:
        """Recompute the library-local logs from ``_lib_theta`` (K,), in place."""
        k = self._rows.pad
        np.log(self._lib_theta, out=self._lib_log_theta[:k])
        np.log1p(-self._lib_theta, out=self._lib_log_1m_theta[:k])
        np.copyto(self._untested_log_theta, self._lib_log_theta, where=self._lib_untested)

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
        return self._num_alive == 0 or self._num_proven > 0

    def most_probable_path(self) -> int:
        """i* = argmax over alive paths of p_i (first index on ties): the MaxProbReg path."""
        return int(np.where(self._alive, self._logp, -np.inf).argmax())

    def region_path(self, rule: str, edge_costs: FloatArray) -> int:
        """The alive path the region rule ``rule`` picks (:mod:`drd_planner.core.region_rule`).

        ``"probability"`` is :meth:`most_probable_path`; ``"per_check"`` ranks by p_i per expected check
        (:class:`~drd_planner.core.proof_order.ProofOrder`, built on first use with ``edge_costs``).
        """
        if check_region_rule(rule) == "probability":
            return self.most_probable_path()
        if self._proof_order is None:
            self._proof_order = ProofOrder(self._rows, self._theta, edge_costs, checked=self._tested)
        alive = self._alive_ids
        return self._proof_order.best_path(self._logp[alive], alive)

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
        return self._incidence(cand, self._alive_through[cand])

    def _incidence(self, cand: IntArray, counts: IntArray) -> tuple[IntArray, IntArray]:
        """:meth:`alive_incidence` of the (c,) int64 ``cand`` with their (c,) alive path counts."""
        if cand.size == 0:
            return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
        paths = np.concatenate([self._alive_paths_through(e) for e in cand.tolist()])
        return np.arange(cand.size).repeat(counts), paths

    def _alive_paths_through(self, edge: int) -> IntArray:
        """The alive paths through ``edge``, ascending (kept per edge until some path dies)."""
        cached = self._through.get(edge)
        if cached is not None and cached[0] == self._deaths:
            return cached[1]
        if cached is None or cached[1].size != self._alive_through[edge]:  # alive paths only ever die
            column = self._csc.indices[self._csc.indptr[edge] : self._csc.indptr[edge + 1]]
            paths = np.asarray(column[self._alive[column]], dtype=np.int64)
        else:
            paths = cached[1]
        self._through[edge] = (self._deaths, paths)
        return paths

    def edge_log_1m_theta(self, edges: IntArray) -> FloatArray:
        """(c,) log(1 - theta_e) of ``edges`` (0 for an edge no path uses)."""
        return np.asarray(self._lib_log_1m_theta[self._rows.column[edges]], dtype=np.float64)

    def set_theta(self, theta: npt.ArrayLike, *, edges: npt.ArrayLike | None = None) -> None:
        """Replace the bias and make log p_i of every path the sum over its untested edges again.

        Observed edges stay clamped to their outcome; dead paths stay dead. The sums are skipped when
        neither the bias nor any log p_i changed since they were last made.

        Args:
            theta: (E,) new bias in [0, 1]; with ``edges``, one value per edge of ``edges``.
            edges: the edges ``theta`` is for (the others keep their bias), or None for all.
        """
        th = np.asarray(theta, dtype=np.float64).ravel()
        where = np.arange(self._theta.size) if edges is None else np.asarray(edges, dtype=np.int64).ravel()
        if th.shape != where.shape or not _probabilities(th):
            raise ProblemError(f"theta must be ({where.size},) values in [0, 1]")
        th = np.minimum(np.maximum(th, THETA_EPS), 1.0 - THETA_EPS)
        if (th != self._theta[where]).any():
            self._theta[where] = th
            self._new_library_theta(self._theta[self._rows.edges])
        elif not self._differenced:
            return
        self._resum()

    @property
    def library_edges(self) -> IntArray:
        """(K,) sorted ids of the edges some path uses: the edges :meth:`set_library_theta` takes."""
        return self._rows.edges

    def set_library_theta(self, theta: FloatArray | None) -> None:
        """:meth:`set_theta` with the (K,) bias of the :attr:`library_edges`, already known to be in [0, 1].

        The posterior leaf's path: no validation, and nothing scattered through all E edges but the bias.
        None: the bias is known to be unchanged (only log p_i is summed again, if an outcome changed it).
        """
        if theta is None:
            if self._differenced:
                self._resum()
            return
        th = np.maximum(theta, THETA_EPS)
        np.minimum(th, 1.0 - THETA_EPS, out=th)
        if (th != self._lib_theta).any():
            self._theta[self._rows.edges] = th
            self._new_library_theta(th)
        elif not self._differenced:
            return
        self._resum()

    def _new_library_theta(self, theta: FloatArray) -> None:
        """Take the (K,) clamped bias of the library edges (owned from now on): logs and proof order."""
        self._lib_theta = theta
        self._library_logs()
        if self._proof_order is not None:
            self._proof_order.set_library_theta(theta, changed=True)

    def _resum(self) -> None:
        """Sum log p_i of every alive path again (the dead paths' log p_i is never read again)."""
        if self._num_alive == self._library.num_paths:
            self._logp = self._path_sums()
        else:
            self._logp[self._alive_ids] = self._path_sums(self._alive_ids)
        self._differenced = False

    def _path_sums(self, paths: IntArray | None = None) -> FloatArray:
        """(r,) sum of log theta over the untested edges of ``paths`` (None: all m), each in path order.

        Added down the columns of the library's table (:attr:`~drd_planner.core.path_rows.PathRows.table`,
        :func:`~drd_planner.core.path_rows.column_sums`), one term after the other as a sparse row sum adds
        them (a ``sum`` along a path's own terms may add pairwise), so a path's sum does not depend on which
        paths are summed with it.
        """
        table = self._rows.table if paths is None else self._rows.table[:, paths]
        return column_sums(self._untested_log_theta[table])

    def observe(self, edge: int, free: bool) -> None:
        """Clamp ``edge`` to its outcome and update the paths through it."""
        if self._tested[edge]:
            return
        self._tested[edge] = True
        k = int(self._rows.column[edge])  # the pad slot K for a non-library edge
        self._untested_log_theta[k] = 0.0
        self._lib_untested[k] = False
        paths = self._csc.indices[self._csc.indptr[edge] : self._csc.indptr[edge + 1]]
        if paths.size == 0:
            return
        if self._proof_order is not None:
            self._proof_order.mark_checked(edge, paths)
        if free:
            self._logp[paths] -= self._lib_log_theta[k]
            remaining = self._remaining[paths] - 1
            self._remaining[paths] = remaining
            proven = paths[remaining == 0]
            if proven.size:
                self._logp[proven] = 0.0
                self._num_proven += int(proven.size)  # every edge checked free: alive
            self._differenced = True
            return
        dying = paths[self._alive[paths]]
        if dying.size == 0:
            return
        self._alive[dying] = False
        self._alive_ids = self._alive_ids[self._alive[self._alive_ids]]
        self._num_alive -= int(dying.size)
        self._deaths += 1
        self._alive_through[self._rows.edges] -= self._rows.edge_counts(dying)
