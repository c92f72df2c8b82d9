"""The world database: which edges are free in which sampled world."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.exceptions import ProblemError


@dataclass(frozen=True)
class WorldDatabase:
    """Sampled worlds (hypotheses) with their edge outcomes and path validity.

    Attributes:
        X: (n, E) bool, X[h, e] is True when edge e is collision-free in world h.
        R: (n, m) bool, R[h, i] is True when library path i is valid (all edges free) in world h.
        train_ids: (n_train,) int64 row indices of the training worlds.
        test_ids: (n_test,) int64 row indices of the held-out test worlds.
        prior: (n,) float64 non-negative prior weights, or None for uniform.
    """

    X: BoolArray
    R: BoolArray
    train_ids: IntArray
    test_ids: IntArray
    prior: FloatArray | None = None

    def __post_init__(self) -> None:
        x = np.asarray(self.X, dtype=bool)
        r = np.asarray(self.R, dtype=bool)
        if x.ndim != 2 or r.ndim != 2 or x.shape[0] != r.shape[0]:
            raise ProblemError(f"X (n, E) and R (n, m) must share n; got {x.shape} and {r.shape}")
        n = x.shape[0]
        train = np.asarray(self.train_ids, dtype=np.int64).ravel()
        test = np.asarray(self.test_ids, dtype=np.int64).ravel()
        for name, ids in (("train", train), ("test", test)):
            if ids.size and (ids.min() < 0 or ids.max() >= n):
                raise ProblemError(f"{name} world ids must lie in [0, {n})")
            if np.unique(ids).size != ids.size:
                raise ProblemError(f"{name} world ids repeat")
        if np.intersect1d(train, test).size:
            raise ProblemError("train and test worlds overlap")
        if self.prior is not None:
            prior = np.asarray(self.prior, dtype=np.float64)
            if prior.shape != (n,) or not np.all(np.isfinite(prior)) or np.any(prior < 0):
                raise ProblemError("prior must be (n,) finite and non-negative")
            object.__setattr__(self, "prior", prior)
        object.__setattr__(self, "X", x)
        object.__setattr__(self, "R", r)
        object.__setattr__(self, "train_ids", train)
        object.__setattr__(self, "test_ids", test)

    @property
    def num_worlds(self) -> int:
        """N."""
        return int(self.X.shape[0])

    def weights(self, ids: npt.ArrayLike) -> FloatArray:
        """Prior weights of the worlds ``ids`` (ones when the prior is uniform)."""
        idx = np.asarray(ids, dtype=np.int64)
        if self.prior is None:
            return np.ones(idx.size, dtype=np.float64)
        return np.asarray(self.prior[idx], dtype=np.float64)

    def subset(self, train_ids: npt.ArrayLike, test_ids: npt.ArrayLike) -> WorldDatabase:
        """The same worlds with another split."""
        return WorldDatabase(self.X, self.R, np.asarray(train_ids), np.asarray(test_ids), self.prior)
