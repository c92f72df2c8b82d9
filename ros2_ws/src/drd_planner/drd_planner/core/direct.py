"""DiRECt: decision-region edge cutting over a finite world database (docs/algorithms.md, "DiRECt").

One ECD problem per library path r (its region R_r against the *atoms* outside it: worlds with
identical path-validity rows), plus a null ECD over all atoms when some training world has no
valid path, combined by Noisy-OR. The greedy step maximises the expected reduction of the
remaining product per unit cost (the corrected Alg. 1), in log space, for all tests at once:

    w_r(t, x) = 1/2 (T_x^2 - a_x^2 - Q_x + S_x)        (section 3.4)

with atom masses C_x (S x tests), T_x = sum C_x, Q_x = sum C_x^2, a_x = M^T C_x and
S_x = M^T (C_x o C_x). Regions with identical membership over the active atoms are merged and
counted with multiplicity; regions with no active world degenerate to the null weight
1/2 (T_x^2 - Q_x). With a uniform prior all masses are integer counts, so the matrix products run
exactly in float32 BLAS and zero weights are detected exactly.

Optional region colouring (variant (c)): regions that never share a world are grouped into one
ECD (Welsh-Powell greedy colouring of the overlap graph), w_k = 1/2 (T^2 - Q - sum_{r in k}(a_r^2 - S_r)).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp

from drd_planner.arrays import BoolArray, FloatArray, IntArray, unique_bool_rows
from drd_planner.exceptions import ProblemError

#: Relative tolerance for ties between test scores (first test wins).
TIE_RTOL = 1e-9
#: Counts below this many worlds run exactly in float32 (sums of squared counts stay < 2**24).
_FLOAT32_EXACT_WORLDS = 4096
#: Weighted priors: a weight below this fraction of its version space's squared mass is zero
#: (the closed form cancels terms of size mass^2, so its rounding error is a few ulps of that).
_ZERO_RTOL = 64 * float(np.finfo(np.float64).eps)


def greedy_region_colouring(R: npt.ArrayLike) -> IntArray:
    """Colour regions so that regions sharing a world never share a colour (Welsh-Powell order).

    Args:
        R: (n, m) bool world x region membership.

    Returns:
        (m,) int64 colour per region, colours numbered from 0.
    """
    r = np.asarray(R, dtype=np.float64)
    overlap = (r.T @ r) > 0
    np.fill_diagonal(overlap, False)
    degree = overlap.sum(1)
    order = np.argsort(-degree, kind="stable")
    colour = np.full(r.shape[1], -1, dtype=np.int64)
    for region in order.tolist():
        used = set(colour[overlap[region] & (colour >= 0)].tolist())
        c = 0
        while c in used:
            c += 1
        colour[region] = c
    return colour


def pick_best_test(log_expected: npt.ArrayLike, costs: npt.ArrayLike) -> int:
    """Index of the test with the largest expected reduction per cost, (1 - E) / c.

    ``log_expected`` (k,) is log E, E = the expected remaining fraction of the Noisy-OR product.
    With hundreds of ECDs, E is often far below machine epsilon, so 1 - E rounds to 1 for every
    test; ties of the score (within TIE_RTOL) are therefore broken by the smaller log E, which is
    the same ordering, then by the first index.
    """
    log_e = np.asarray(log_expected, dtype=np.float64)
    score = -np.expm1(log_e) / np.asarray(costs, dtype=np.float64)
    best = score.max()
    near = np.flatnonzero(score >= best - TIE_RTOL * abs(best))
    sub = log_e[near]
    lowest = sub.min()
    if not np.isfinite(lowest):
        return int(near[int(np.argmin(sub))])
    tie = sub <= lowest + TIE_RTOL * max(1.0, abs(lowest))
    return int(near[int(np.argmax(tie))])


@dataclass(frozen=True)
class _EcdGroups:
    """The ECD problems over the active atoms of one selection.

    Attributes:
        members: (S, U) 0/1 membership of each distinct region holding active mass, or None.
        multiplicity: (G,) how many ECDs share each weight row (after ``colour_sum``, if any).
        null_count: ECDs that degenerate to the all-atoms null weight (the null ECD included).
        colour_sum: (G, U) sparse sum of region rows into colour groups, or None without colouring.
    """

    members: npt.NDArray[np.floating] | None
    multiplicity: FloatArray
    null_count: int
    colour_sum: sp.csr_array | None = None


@dataclass(frozen=True)
class DirectChoice:
    """A DiRECt selection.

    Attributes:
        edge: the chosen edge id.
        score: expected fraction of the remaining Noisy-OR product removed, per unit cost.
        log_expected_remaining: log of the expected remaining fraction (finer than score near 1).
    """

    edge: int
    score: float
    log_expected_remaining: float


class DirectSelector:
    """Greedy DiRECt test selection on a fixed training database.

    Args:
        X: (n, E) bool outcomes of the training worlds.
        R: (n, m) bool path validity of the training worlds.
        edge_costs: (E,) positive costs.
        prior: (n,) positive prior weights, or None for uniform (exact integer arithmetic).
        colouring: group never-overlapping regions into one ECD (variant (c)).
        candidate_edges: restrict tests to these edge ids (default: every edge).
    """

    def __init__(
        self,
        X: npt.ArrayLike,
        R: npt.ArrayLike,
        edge_costs: npt.ArrayLike,
        *,
        prior: npt.ArrayLike | None = None,
        colouring: bool = False,
        candidate_edges: npt.ArrayLike | None = None,
    ) -> None:
        self._X = np.asarray(X, dtype=bool)
        self._R = np.asarray(R, dtype=bool)
        n = self._X.shape[0]
        if self._R.shape[0] != n:
            raise ProblemError("X and R must have the same number of worlds")
        self._costs = np.asarray(edge_costs, dtype=np.float64)
        if self._costs.shape != (self._X.shape[1],) or np.any(self._costs <= 0):
            raise ProblemError("edge costs must be (E,) and positive")
        self._uniform = prior is None
        self._prior = np.ones(n) if prior is None else np.asarray(prior, dtype=np.float64)
        if self._prior.shape != (n,) or np.any(self._prior <= 0) or not np.all(np.isfinite(self._prior)):
            raise ProblemError("the DiRECt prior must be (n,) finite and positive")
        if candidate_edges is None:
            self._candidates = np.arange(self._X.shape[1], dtype=np.int64)
        else:
            self._candidates = np.unique(np.asarray(candidate_edges, dtype=np.int64))
        # Every edge a candidate: a view, not a copy (online trees share the prior's X across queries).
        self._Xc = self._X if candidate_edges is None else self._X[:, self._candidates]
        # Atoms: worlds with identical region-membership rows.
        self._atom_regions, self._atom_of = unique_bool_rows(self._R)  # (S, m), (n,)
        self._null_ecd = bool((~self._R.any(axis=1)).any())
        self._colour = greedy_region_colouring(self._R) if colouring else None
        self._exact = self._uniform and n < _FLOAT32_EXACT_WORLDS
        self._dtype = np.float32 if self._exact else np.float64
        self._flops = 0

    @property
    def num_worlds(self) -> int:
        """n, the number of training worlds."""
        return int(self._X.shape[0])

    @property
    def matmul_flops(self) -> int:
        """Floating-point operations spent in the ECD-weight matrix products so far."""
        return self._flops

    @property
    def has_null_ecd(self) -> bool:
        """True when some training world has no valid path (adds the all-atoms ECD)."""
        return self._null_ecd

    @property
    def num_ecds(self) -> int:
        """Number of ECD problems combined by Noisy-OR."""
        groups = self._R.shape[1] if self._colour is None else int(self._colour.max(initial=-1) + 1)
        return groups + int(self._null_ecd)

    def _is_zero(self, w: FloatArray, mass: float | FloatArray) -> BoolArray:
        """Zero weights: exact for integer counts; else within rounding of the branch's mass^2."""
        if self._exact:
            return np.asarray(w <= 0.0)
        return np.asarray(w <= _ZERO_RTOL * np.asarray(mass) ** 2)

    def select(
        self,
        active: npt.ArrayLike,
        *,
        regions: npt.ArrayLike | None = None,
        candidates: npt.ArrayLike | None = None,
    ) -> DirectChoice | None:
        """The best test for the version space ``active`` (training-world row ids), or None.

        None means the DRD is solved on the database (all active worlds lie in one region, or share
        one atom) or no test splits the active worlds.

        Args:
            active: training-world row ids consistent with the observations so far.
            regions: restrict the DRD to these regions (IncDRD); atoms and the null ECD are then
                taken over the restricted membership of the active worlds. Not with colouring.
            candidates: restrict this selection to these edge ids (e.g. the edges of the most
                probable region, the DiRECt analogue of MaxProbReg); ECD weights are unchanged.
        """
        act = np.asarray(active, dtype=np.int64)
        if act.size == 0:
            return None
        weights = self._prior[act]
        members, local, null_ecd = self._atoms(act, regions)
        num_atoms = members.shape[0]
        mass = np.bincount(local, weights=weights, minlength=num_atoms).astype(np.float64)  # c, (S,)
        total = float(mass.sum())
        groups = self._groups(members, null_ecd)
        w_now, w0_now = self._weights_now(mass, groups)
        if np.any(self._is_zero(w_now, total)) or (groups.null_count and self._is_zero(np.array([w0_now]), total)[0]):
            return None
        x_act, split_cols, informative = self._informative(act, candidates)
        if informative.size == 0:
            return None
        xi = x_act[:, split_cols].astype(self._dtype)
        onehot = sp.csr_array((weights.astype(self._dtype), (local, np.arange(act.size))), shape=(num_atoms, act.size))
        c1 = np.asarray(onehot @ xi)  # (S, Ti) mass of atom s with x_t = 1
        c0 = mass.astype(self._dtype)[:, None] - c1
        (t0, l0), (t1, l1) = (self._log_remaining(cx, groups, w_now, w0_now) for cx in (c0, c1))
        with np.errstate(divide="ignore"):
            log_p0 = np.log(t0 / total)
            log_p1 = np.log(t1 / total)
        log_expected = np.logaddexp(log_p0 + l0, log_p1 + l1)
        best = pick_best_test(log_expected, self._costs[self._candidates[informative]])
        return DirectChoice(
            int(self._candidates[informative[best]]),
            float(-np.expm1(log_expected[best]) / self._costs[self._candidates[informative[best]]]),
            float(log_expected[best]),
        )

    def _atoms(self, act: IntArray, regions: npt.ArrayLike | None) -> tuple[BoolArray, IntArray, bool]:
        """((S, m) region membership of the active atoms, (k,) atom of each active world, null ECD).

        With ``regions`` (IncDRD) atoms are taken over the restricted membership of the active worlds.
        """
        if regions is None:
            atom_ids, local = np.unique(self._atom_of[act], return_inverse=True)
            members = self._atom_regions[atom_ids]  # (S, m)
            null_ecd = self._null_ecd
        else:
            if self._colour is not None:
                raise ProblemError("region subsets (IncDRD) cannot be combined with colouring")
            cols = np.asarray(regions, dtype=np.int64)
            members, local = unique_bool_rows(self._R[np.ix_(act, cols)])
            null_ecd = bool((~members.any(axis=1)).any())
        return members, np.asarray(local).ravel(), null_ecd

    def _informative(
        self, act: IntArray, candidates: npt.ArrayLike | None
    ) -> tuple[npt.NDArray[Any], IntArray, IntArray]:
        """(gathered outcome columns of the active worlds, split columns among them, informative tests).

        Informative tests are those the active worlds disagree on; only the candidate columns are
        gathered (a node's candidates are one path's edges, X has all). Tests are indices into the
        candidate edges.
        """
        cand_cols = None
        if candidates is not None:
            cand_cols = np.flatnonzero(np.isin(self._candidates, np.asarray(candidates, dtype=np.int64)))
        x_act = self._Xc[act] if cand_cols is None else self._Xc[np.ix_(act, cand_cols)]
        free_count = x_act.sum(axis=0)
        split_cols = np.flatnonzero((free_count > 0) & (free_count < act.size))
        informative = split_cols if cand_cols is None else cand_cols[split_cols]
        return x_act, split_cols, informative

    def _log_remaining(
        self, cx: npt.NDArray[Any], groups: _EcdGroups, w_now: FloatArray, w0_now: float
    ) -> tuple[FloatArray, FloatArray]:
        """((T,) mass of outcome x per test, (T,) log of the ECD weight left after it over the weight now).

        ``cx``: (S, T) mass of each active atom with outcome x of each informative test.
        """
        num_atoms, k = cx.shape
        stacked = np.empty((num_atoms, 2 * k), dtype=self._dtype)  # [C_x | C_x o C_x]
        stacked[:, :k] = cx
        np.multiply(cx, cx, out=stacked[:, k:])
        tx = cx.sum(axis=0, dtype=np.float64)
        qx = stacked[:, k:].sum(axis=0, dtype=np.float64)
        w0_x = 0.5 * (tx * tx - qx)
        with np.errstate(divide="ignore"):
            lx = np.zeros(k)
            if groups.members is not None:
                wx = self._group_weights(stacked, groups, tx, qx)
                if not self._exact:  # exact integer weights are already exactly zero
                    wx = np.where(self._is_zero(wx, tx), 0.0, wx)
                mult = groups.multiplicity
                lx += mult @ np.log(wx) - float(mult @ np.log(w_now))
            if groups.null_count:
                w0z = np.where(self._is_zero(w0_x, tx), 0.0, w0_x)
                lx += groups.null_count * (np.log(w0z) - np.log(w0_now))
        return tx, lx

    def _groups(self, members: BoolArray, null_ecd: bool) -> _EcdGroups:
        """The ECD problems over the active atoms ``members`` (S, m).

        Without colouring, regions with identical membership are merged and counted with
        multiplicity; with colouring, region rows are summed into their colour's ECD. Regions with
        no active mass degenerate to the null weight and are only counted.
        """
        has_mass = members.any(axis=0)
        if self._colour is None:
            active_regions = members[:, has_mass]
            null_count = int((~has_mass).sum()) + int(null_ecd)
            if active_regions.shape[1] == 0:
                return _EcdGroups(None, np.zeros(0), null_count)
            # Merge regions with identical membership: unique over bit-packed columns (fast hashing).
            packed = np.ascontiguousarray(np.packbits(active_regions, axis=0).T)
            keys = packed.view(np.dtype((np.void, packed.shape[1]))).ravel()
            _, first, counts = np.unique(keys, return_index=True, return_counts=True)
            cols = active_regions[:, first]
            return _EcdGroups(cols.astype(self._dtype), counts.astype(np.float64), null_count)
        colours = self._colour[has_mass]
        used = np.unique(colours)
        null_count = int(self._colour.max() + 1 - used.size) + int(null_ecd)
        colour_sum = sp.csr_array(
            (np.ones(colours.size), (np.searchsorted(used, colours), np.arange(colours.size))),
            shape=(used.size, colours.size),
        )
        members_f = members[:, has_mass].astype(self._dtype)
        return _EcdGroups(members_f if colours.size else None, np.ones(used.size), null_count, colour_sum)

    def _group_weights(
        self, stacked: npt.NDArray[np.floating], groups: _EcdGroups, tx: FloatArray, qx: FloatArray
    ) -> FloatArray:
        """(G, tests) ECD weights under one outcome (float64).

        ``stacked`` is (S, 2 tests): the atom masses C_x next to their squares C_x o C_x.
        """
        members = groups.members
        assert members is not None
        both = members.T @ stacked
        self._flops += 2 * members.shape[0] * members.shape[1] * stacked.shape[1]
        k = stacked.shape[1] // 2
        # With integer counts below 2**12 worlds every term is an integer below 2**24, so the
        # arithmetic stays exact in float32; otherwise it runs in float64.
        a = both[:, :k]
        diff = a * a
        diff -= both[:, k:]  # (regions, tests): squared region mass minus its atoms' squares
        if groups.colour_sum is not None:
            diff = np.asarray(groups.colour_sum @ diff.astype(np.float64), dtype=self._dtype)
        outside = (tx * tx - qx).astype(self._dtype)
        np.subtract(outside[None, :], diff, out=diff)
        return np.asarray(diff, dtype=np.float64) * 0.5

    def _weights_now(self, mass: FloatArray, groups: _EcdGroups) -> tuple[FloatArray, float]:
        """Current ECD weights (G,) and null weight for atom masses ``mass`` (S,)."""
        t = float(mass.sum())
        q = float((mass * mass).sum())
        w0 = 0.5 * (t * t - q)
        if groups.members is None:
            return np.zeros(0), w0
        c = mass.astype(self._dtype)[:, None]
        w = self._group_weights(np.concatenate([c, c * c], axis=1), groups, np.array([t]), np.array([q]))
        return w[:, 0], w0
