"""The one-node tree of a query whose switch threshold is 1: BiSECt from the root, no DiRECt node to grow.

With eta = 1 the combined method switches to BiSECt before its first check (the root's consistent fraction, 1,
is at or below eta), so the DiRECt tree is never walked: only its root's bias (the training worlds' free
fraction of each library edge) and, for the posterior leaf, the training worlds' library-edge outcomes are
read. Validation picks eta 1 for new queries on every shipped prior (random queries are short; no tree beats
BiSECt on them), so the planner builds this instead of a :class:`~drd_planner.core.online_tree.LazyDirectTree`
for them: the same numbers (the root's bias is computed exactly as the lazy tree's), without the tree's
per-query set-up.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray
from drd_planner.core.library import PathLibrary
from drd_planner.core.posterior import TrainingOutcomes
from drd_planner.core.region_rule import check_region_rule
from drd_planner.core.tree import NO_CHILD, NO_EDGE, leaf_bias, node_summary
from drd_planner.exceptions import ProblemError

__all__ = ["RootTree"]


class RootTree:
    """A tree with its root only (implements :class:`~drd_planner.core.tree.TreeNodes`).

    Args:
        library_outcomes: (n, K) bool training outcomes of the library's edges (``library.library_edges``).
        library: the query's m paths.
        weights: (n,) positive prior weights, or None for uniform.
        region_rule: the rule BiSECt follows after the switch.
    """

    def __init__(
        self,
        library_outcomes: npt.ArrayLike,
        library: PathLibrary,
        *,
        weights: npt.ArrayLike | None = None,
        region_rule: str,
    ) -> None:
        x = np.asarray(library_outcomes, dtype=bool)
        self._lib_edges = library.library_edges
        if x.ndim != 2 or x.shape[1] != self._lib_edges.size or x.shape[0] == 0:
            raise ProblemError(
                f"a root tree needs (n >= 1, {self._lib_edges.size}) library-edge outcomes, got {x.shape}"
            )
        self._x = x
        self._library = library
        self._prior = None if weights is None else np.asarray(weights, dtype=np.float64)
        self._weights = np.ones(x.shape[0]) if self._prior is None else self._prior
        self._rule = check_region_rule(region_rule)

    @property
    def num_edges(self) -> int:
        """E."""
        return self._library.num_edges

    @property
    def num_paths(self) -> int:
        """M."""
        return self._library.num_paths

    @property
    def num_nodes(self) -> int:
        """1."""
        return 1

    @property
    def num_worlds(self) -> int:
        """n, the training worlds."""
        return int(self._x.shape[0])

    @property
    def region_rule(self) -> str:
        """The rule BiSECt follows after the switch."""
        return self._rule

    @cached_property
    def training_outcomes(self) -> TrainingOutcomes:
        """The training worlds' library-edge outcomes for the posterior leaf (built on first use)."""
        return TrainingOutcomes(self._x, self._lib_edges, self.num_edges, weights=self._prior)

    def node_edge(self, node: int) -> int:
        """NO_EDGE: the root is a leaf."""
        return NO_EDGE

    def node_child(self, node: int, free: bool) -> int:
        """NO_CHILD."""
        return NO_CHILD

    def node_fraction(self, node: int) -> float:
        """1.0: every training world is consistent at the root (0.0 without prior mass)."""
        return 1.0 if float(self._weights.sum()) > 0 else 0.0

    def bias(self, node: int, *, alpha: float = 0.99) -> FloatArray:
        """(E,) BiSECt's bias at the root, as :class:`~drd_planner.core.online_tree.LazyDirectTree` computes it."""
        valid: BoolArray = self._valid()
        free, _ = node_summary(self._weights, self._x.astype(np.float64), valid.astype(np.float64))
        return leaf_bias(self.num_edges, self._lib_edges, free, alpha=alpha)

    def _valid(self) -> BoolArray:
        """(n, m) whether each library path is free in each world (from the library edges' outcomes only)."""
        blocked = (~self._x).astype(np.float32)
        # The (m, K) incidence over the library's own edges, dense (sparse column indexing costs more).
        paths = self._library.path_edges
        rows = np.repeat(np.arange(len(paths)), [p.size for p in paths])
        cols = np.searchsorted(self._lib_edges, np.concatenate(paths))
        incidence = np.zeros((len(paths), self._lib_edges.size), dtype=np.float32)
        incidence[rows, cols] = 1.0
        counts = incidence @ blocked.T
        valid: BoolArray = np.asarray(counts == 0, dtype=bool).T
        return valid
