"""Which path (region) BiSECt and the DiRECt tree try to prove next: the region rules.

Both methods restrict their candidate tests to the edges of one library path (MaxProbReg, docs/algorithms.md,
"The most probable path (MaxProbReg) and ties"). The paper's rule, ``"probability"``, takes the path most
likely to be free. That ignores what proving it costs: a path of 12 untested edges that is free with
probability 0.50 is a worse bet than one of 3 untested edges that is free with probability 0.45.

``"per_check"`` takes the path with the highest probability of being proven free *per expected check
spent on it*. The derivation, for independent edges (edge e free with probability theta_e, check cost
c_e):

* Proving path i means checking its untested edges until one is blocked (the path is dead) or all are
  free (proven). Checked in the order c_e / (1 - theta_e) ascending (cheap and likely blocked first),
  the expected cost of resolving the path is minimal among all orders (the classic order for a series
  of tests that stops at the first failure) and equals::

      E_i = sum_{k=1..r_i} c_(k) * prod_{j<k} theta_(j)

  over its r_i untested edges in that order: edge k is checked only if the k - 1 before it were free.
* For paths that share no untested edge, trying them one at a time in decreasing order of
  p_i / E_i, with p_i = prod theta_e the probability that path i is free, minimises the expected cost
  of finding a free one (the ratio rule for satisficing search over alternatives, Simon & Kadane 1975:
  an exchange of two neighbouring paths in the order changes the expected cost by
  E_a E_b (p_b / E_b - p_a / E_a) up to a common positive factor).

Library paths do share edges, so the rule is a heuristic there, as MaxProbReg is; whether it needs
fewer checks is measured (``scripts/experiments/bench_region_rule.py``). Ties go to the lower path index, as with
MaxProbReg. With unit costs and all theta equal the two rules differ only through r_i.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray, IntArray
from drd_planner.core.library import PathLibrary
from drd_planner.core.path_rows import PathRows
from drd_planner.core.proof_order import ProofOrder
from drd_planner.exceptions import ProblemError

__all__ = [
    "DEFAULT_REGION_RULE",
    "REGION_RULES",
    "NodeRegionInputs",
    "check_region_rule",
    "expected_proof_costs",
    "node_region_path",
    "region_scores",
]

#: The region rules: the paper's MaxProbReg (most probable path) and probability per expected check.
REGION_RULES: Final = ("probability", "per_check")
#: The rule used unless one is asked for by name (the paper's).
DEFAULT_REGION_RULE: Final = "probability"


def check_region_rule(rule: str) -> str:
    """``rule`` if it is one of :data:`REGION_RULES`, else ProblemError naming them."""
    if rule not in REGION_RULES:
        raise ProblemError(f"unknown region rule {rule!r}; known: {', '.join(REGION_RULES)}")
    return rule


def expected_proof_costs(
    indptr: npt.NDArray[np.integer],
    indices: npt.NDArray[np.integer],
    theta: FloatArray,
    edge_costs: FloatArray,
    done: BoolArray,
    rows: BoolArray,
) -> FloatArray:
    """E_i, the expected cost of resolving each path by checking its untested edges (module docstring).

    Args:
        indptr: (m + 1,) CSR row pointers of the path-edge incidence.
        indices: (nnz,) edge ids of each path, row by row.
        theta: (E,) probability that each edge is free, in (0, 1).
        edge_costs: (E,) positive check costs.
        done: (E,) edges already checked (they cost nothing more).
        rows: (m,) the paths to score; the others get 0.

    Returns:
        (m,) float64 expected cost (0 for a path with nothing left to check or not in ``rows``).
    """
    rows_table = PathRows(indptr, indices, np.asarray(theta).size)
    return ProofOrder(rows_table, theta, edge_costs, checked=done).costs(rows)


def region_scores(rule: str, log_p: FloatArray, proof_costs: FloatArray) -> FloatArray:
    """(m,) the score each path is ranked by (higher first); -inf stays -inf (dead paths).

    ``"probability"``: log p_i. ``"per_check"``: log p_i - log E_i (a path with E_i = 0, nothing left
    to check, scores +inf: it is proven).
    """
    check_region_rule(rule)
    if rule == "probability":
        return log_p
    with np.errstate(divide="ignore", invalid="ignore"):
        score = log_p - np.log(proof_costs)
    return np.where(np.isneginf(log_p), -np.inf, score)


def node_region_path(
    rule: str,
    support: FloatArray,
    free_fraction: FloatArray,
    incidence: tuple[npt.NDArray[np.integer], npt.NDArray[np.integer]],
    edge_costs: FloatArray,
    checked: BoolArray,
    *,
    alpha: float = 0.99,
) -> int | None:
    """The path a DiRECt tree node restricts its tests to, or None when no path is valid in its worlds.

    Args:
        rule: one of :data:`REGION_RULES`.
        support: (m,) weighted count of the node's consistent worlds in which each path is valid.
        free_fraction: (E,) weighted free fraction of each edge over those worlds (only path edges used).
        incidence: ``(indptr, indices)`` of the (m, E) CSR path-edge incidence.
        edge_costs: (E,) positive check costs.
        checked: (E,) edges checked on the way from the root to the node (they cost nothing more).
        alpha: theta = alpha * free fraction + (1 - alpha) / 2, as the tree's leaf bias, so no edge is
            certain before it is checked.
    """
    if support.max() <= 0:
        return None
    if check_region_rule(rule) == "probability":
        return int(np.argmax(support))
    theta = alpha * np.asarray(free_fraction, dtype=np.float64) + (1.0 - alpha) * 0.5
    valid = support > 0
    costs = expected_proof_costs(incidence[0], incidence[1], theta, edge_costs, checked, valid)
    with np.errstate(divide="ignore"):
        log_p = np.where(valid, np.log(np.where(valid, support, 1.0)), -np.inf)
    return int(np.argmax(region_scores(rule, log_p, costs)))


@dataclass(frozen=True)
class NodeRegionInputs:
    """What a tree node needs to pick its path by a region rule other than the paper's.

    Attributes:
        rule: one of :data:`~drd_planner.core.region_rule.REGION_RULES`.
        X: (n, E) bool training outcomes.
        library: the m paths.
        edge_costs: (E,) positive check costs.
    """

    rule: str
    X: npt.NDArray[np.bool_]
    library: PathLibrary
    edge_costs: FloatArray

    def path(self, support: FloatArray, active: IntArray, weights: FloatArray, checked: BoolArray) -> int | None:
        """The node's path by ``rule`` (:func:`node_region_path`); ``checked``: (E,) edges checked above it."""
        lib = self.library.library_edges
        w = weights[active]
        free = np.zeros(self.X.shape[1])
        if w.sum() > 0:
            free[lib] = (w @ self.X[np.ix_(active, lib)]) / w.sum()
        csr = self.library.incidence
        return node_region_path(self.rule, support, free, (csr.indptr, csr.indices), self.edge_costs, checked)
