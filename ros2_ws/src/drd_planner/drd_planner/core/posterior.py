"""BiSECt's bias re-conditioned on every outcome: the authors' ``update_posterior`` option.

The paper's benchmark keeps BiSECt's bias fixed after the switch from the tree (ALGORITHMS.md 3.6,
``update_posterior=false``): theta is the free fraction of the training worlds consistent with the
tree node, and later outcomes only clamp their own edge. With the posterior update every outcome
also removes the training worlds it contradicts, and theta is recomputed from those that remain.

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
        self.marginal: FloatArray = (
            self.free_mass / self.total_mass if self.total_mass > 0 else np.full(lib.size, 0.5)
        )

    @property
    def num_worlds(self) -> int:
        """N."""
        return int(self.world_free.shape[0])

    def free_mass_of(self, rows: IntArray) -> FloatArray:
        """(K,) weighted count of ``rows`` in which each library edge is free."""
        x = self.world_free[rows]
        if self.uniform:
            return np.asarray(x.sum(axis=0), dtype=np.float64)
        return np.asarray(self.weights[rows] @ x, dtype=np.float64)


class ConsistentWorldsBias:
    """theta from the training worlds consistent with the observations so far, shrunk by kappa.

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
        self._alpha = alpha
        self._consistent = np.ones(outcomes.num_worlds, dtype=bool)
        self._mass = outcomes.total_mass
        self._free_mass = outcomes.free_mass.copy()
        for edge, free in (observations or {}).items():
            self.observe(edge, free)

    @property
    def num_consistent(self) -> int:
        """How many training worlds agree with every observation so far."""
        return int(self._consistent.sum())

    def observe(self, edge: int, free: bool) -> None:
        """Drop the worlds that disagree with ``edge`` being ``free`` (no-op off the library)."""
        col = int(self._o.column[edge]) if 0 <= edge < self._o.num_edges else -1
        if col < 0:
            return
        dropping = np.flatnonzero(self._consistent & (self._o.world_free[:, col] != free))
        if dropping.size == 0:
            return
        self._consistent[dropping] = False
        if not self._consistent.any():
            self._mass, self._free_mass = 0.0, np.zeros_like(self._free_mass)
            return
        self._mass -= float(self._o.weights[dropping].sum())
        self._free_mass = self._free_mass - self._o.free_mass_of(dropping)

    def theta(self) -> FloatArray:
        """(E,) bias; 0.5 off the library."""
        mass = max(self._mass, 0.0)
        free = np.maximum(self._free_mass, 0.0)
        data = (free + self._kappa * self._o.marginal) / (mass + self._kappa)
        theta = np.full(self._o.num_edges, 0.5)
        theta[self._o.library_edges] = self._alpha * np.clip(data, 0.0, 1.0) + (1.0 - self._alpha) * 0.5
        return theta
