"""BiSECt's bias re-conditioned on every outcome: the authors' ``update_posterior`` option.

The paper's benchmark keeps BiSECt's bias fixed after the switch from the tree (docs/algorithms.md,
"The decision tree and the switch to BiSECt"; ``update_posterior=false``): theta is the free fraction of the
training worlds consistent with the tree node, and later outcomes only clamp their own edge. With the posterior
update every outcome also removes the training worlds it contradicts, and theta is recomputed from those that
remain.

Once few worlds remain their free fractions are noisy (and 0 or 1 on most edges), so the data term
is shrunk toward the global training marginal with a Beta-style pseudo-count kappa::

    theta_e = alpha * (sum_{h in C} w_h X[h, e] + kappa * mean_e) / (sum_{h in C} w_h + kappa)
              + (1 - alpha) / 2

where C is the set of consistent training worlds, w their prior weights scaled to mean 1 (so kappa
counts worlds), and mean_e the weighted free fraction of edge e over all training worlds. With no
consistent world left theta falls back to the global marginal. kappa -> 0 is the pure posterior,
kappa -> infinity is plain BiSECt with the training bias.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.core.world_columns import WorldColumns, pack_rows
from drd_planner.exceptions import ProblemError


class TrainingOutcomes:
    """The training worlds' library-edge outcomes with what every episode's posterior reuses.

    Built once per tree (:attr:`drd_planner.core.tree.DecisionTree.training_outcomes`), so that an
    episode's :class:`ConsistentWorldsBias` only keeps a mask and two running sums.

    Args:
        world_free: (n, K) bool outcome of each library edge in each training world.
        library_edges: (K,) int64 edge ids of the columns of ``world_free``.
        num_edges: E, the length of the bias vectors.
        weights: (n,) non-negative prior weights of the worlds, or None for uniform.
    """

    def __init__(
        self,
        world_free: npt.ArrayLike,
        library_edges: npt.ArrayLike,
        num_edges: int,
        *,
        weights: npt.ArrayLike | None = None,
    ) -> None:
        x = np.asarray(world_free, dtype=bool)
        lib = np.asarray(library_edges, dtype=np.int64)
        if x.ndim != 2 or x.shape[1] != lib.size:
            raise ProblemError(f"world_free must be (n, {lib.size}); got {x.shape}")
        w = np.ones(x.shape[0]) if weights is None else np.asarray(weights, dtype=np.float64)
        if w.shape != (x.shape[0],) or np.any(w < 0) or not np.all(np.isfinite(w)):
            raise ProblemError(f"weights must be ({x.shape[0]},) finite non-negative values")
        mean_w = float(w.mean()) if w.size else 1.0
        self.world_free = x
        self.library_edges = lib
        self.num_edges = num_edges
        self.weights = w / mean_w if mean_w > 0 else w
        self.uniform = weights is None
        self.column = np.full(num_edges, -1, dtype=np.int64)
        self.column[lib] = np.arange(lib.size)
        self.total_mass = float(self.weights.sum())
        self.free_mass: FloatArray = self.free_mass_of(np.arange(x.shape[0]))
        self.marginal: FloatArray = self.free_mass / self.total_mass if self.total_mass > 0 else np.full(lib.size, 0.5)
        self._episodes = 0
        self._columns: WorldColumns | None = None

    @property
    def num_worlds(self) -> int:
        """N."""
        return int(self.world_free.shape[0])

    def episode_columns(self) -> WorldColumns | None:
        """The packed columns an episode's posterior counts with, or None to count over rows.

        Packing costs about one pass over the (n, K) outcomes, so it is done when a second episode asks
        (a tree's outcomes serve every episode of its query), never for outcomes used once. Weighted
        worlds are always summed over rows: bits cannot weigh them.
        """
        if not self.uniform:
            return None
        self._episodes += 1
        if self._episodes < 2:
            return None
        if self._columns is None:
            self._columns = WorldColumns(self.world_free)
        return self._columns

    def free_mass_of(self, rows: IntArray) -> FloatArray:
        """(K,) weighted count of ``rows`` in which each library edge is free."""
        x = self.world_free[rows]
        if self.uniform:  # bytes summed into int32 counts: exact, and faster than bool -> int64
            return np.asarray(x.view(np.uint8).sum(axis=0, dtype=np.int32), dtype=np.float64)
        return np.asarray(self.weights[rows] @ x, dtype=np.float64)


class ConsistentWorldsBias:
    """theta from the training worlds consistent with the observations so far, shrunk by kappa.

    An outcome drops the worlds it contradicts and theta is recomputed only after that. The consistent
    worlds are a packed bit mask when the outcomes have packed columns
    (:meth:`TrainingOutcomes.episode_columns`): an outcome is then one AND of the mask with the edge's
    column, and the free counts a popcount of every column within the mask. Otherwise they are a list
    of rows whose free masses are updated by the dropped rows (or, for uniform weights, counted again
    over the kept ones when they are fewer). Counts of uniform worlds are integers, the same either way.

    Args:
        outcomes: the training worlds (shared by all episodes on one tree).
        pseudo_count: kappa > 0, in worlds.
        alpha: weight of the data term (0.99 in the paper).
        observations: outcomes already known (edge -> free), applied at once.
    """

    def __init__(
        self,
        outcomes: TrainingOutcomes,
        *,
        pseudo_count: float,
        alpha: float = 0.99,
        observations: Mapping[int, bool] | None = None,
    ) -> None:
        if not pseudo_count > 0 or not np.isfinite(pseudo_count):
            raise ProblemError(f"pseudo_count must be a positive number of worlds; got {pseudo_count}")
        self._o = outcomes
        self._kappa = float(pseudo_count)
        self._kappa_marginal = self._kappa * outcomes.marginal
        self._alpha = alpha
        self._columns = outcomes.episode_columns()
        all_worlds = np.ones(outcomes.num_worlds, dtype=bool)
        self._mask = pack_rows(all_worlds)  # the consistent worlds as bits (with packed columns)
        self._rows: IntArray = np.flatnonzero(all_worlds)  # ... as ascending rows (without)
        self._count = outcomes.num_worlds
        self._mass = outcomes.total_mass
        self._free_mass = outcomes.free_mass.copy()
        self._library_theta: FloatArray | None = None  # None: to compute
        for edge, free in (observations or {}).items():
            self.observe(edge, free)

    @property
    def num_consistent(self) -> int:
        """How many training worlds agree with every observation so far."""
        return self._count

    @property
    def library_edges(self) -> IntArray:
        """(K,) the edges :meth:`library_theta` is for."""
        return self._o.library_edges

    def observe(self, edge: int, free: bool) -> bool:
        """Drop the worlds that disagree with ``edge`` being ``free`` (no-op off the library).

        Returns:
            True when some world was dropped (theta changed).
        """
        col = int(self._o.column[edge]) if 0 <= edge < self._o.num_edges else -1
        if col < 0:
            return False
        changed = self._drop_bits(col, free) if self._columns is not None else self._drop_rows(col, free)
        if changed:
            self._library_theta = None
        return changed

    def _drop_bits(self, col: int, free: bool) -> bool:
        """:meth:`observe` on the packed mask: True when some world was dropped."""
        assert self._columns is not None
        column = self._columns.bits[col]
        kept = np.bitwise_and(self._mask, column) if free else np.bitwise_and(self._mask, ~column)
        count = int(np.bitwise_count(kept).sum())
        if count == self._count:  # kept is within the mask: the same count is the same worlds
            return False
        self._mask = kept
        self._count = count
        if self._count == 0:
            self._mass, self._free_mass = 0.0, np.zeros_like(self._free_mass)
        else:
            self._mass = float(self._count)
            words = np.flatnonzero(kept)  # late in an episode the few worlds left fill few words
            if 2 * words.size > kept.size:
                within = np.bitwise_and(self._columns.bits, kept)
            else:
                within = np.bitwise_and(self._columns.bits[:, words], kept[words])
            counts = np.bitwise_count(within, out=within).sum(axis=1, dtype=np.int64)
            self._free_mass = counts.astype(np.float64)
        return True

    def _drop_rows(self, col: int, free: bool) -> bool:
        """:meth:`observe` on the list of rows: True when some world was dropped."""
        agree = self._o.world_free[self._rows, col] == free
        if agree.all():
            return False
        dropping, kept = self._rows[~agree], self._rows[agree]
        self._rows = kept
        self._count = int(kept.size)
        if kept.size == 0:
            self._mass, self._free_mass = 0.0, np.zeros_like(self._free_mass)
        elif self._o.uniform and kept.size < dropping.size:
            self._mass = float(kept.size)
            self._free_mass = self._o.free_mass_of(kept)
        else:
            self._mass -= float(self._o.weights[dropping].sum())
            self._free_mass = self._free_mass - self._o.free_mass_of(dropping)
        return True

    def library_theta(self) -> FloatArray:
        """(K,) bias of the :attr:`library_edges` (computed after a change only; do not modify)."""
        if self._library_theta is None:
            mass = max(self._mass, 0.0)
            # Counted free masses are never negative; masses updated by difference may round below 0.
            free = self._free_mass if self._columns is not None else np.maximum(self._free_mass, 0.0)
            theta = np.add(free, self._kappa_marginal)
            np.divide(theta, mass + self._kappa, out=theta)
            np.maximum(theta, 0.0, out=theta)
            np.minimum(theta, 1.0, out=theta)
            np.multiply(theta, self._alpha, out=theta)
            np.add(theta, (1.0 - self._alpha) * 0.5, out=theta)
            self._library_theta = theta
        return self._library_theta

    def theta(self) -> FloatArray:
        """(E,) bias; 0.5 off the library."""
        theta = np.full(self._o.num_edges, 0.5)
        theta[self._o.library_edges] = self.library_theta()
        return theta
