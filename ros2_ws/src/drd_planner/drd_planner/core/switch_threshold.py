"""Choose the tree-to-BiSECt switch threshold eta on held-out *training* worlds.

The paper treats eta (hand over to BiSECt once the consistent fraction of training worlds is at
or below eta) as a tuning parameter. Which value is best depends on the domain: on sets whose
worlds share structure (walls, baffles, canyons) a deep tree pays off, while on sets with many
infeasible training worlds (the HERB arm set) the node-conditioned leaf bias can be worse than the
global one, and switching at the root (eta = 1, i.e. plain BiSECt with the training bias) is best.

:func:`select_switch_threshold` decides this from the training worlds alone: it holds out a
seeded fraction of the *feasible* training worlds (the test protocol draws test worlds among
feasible ones), builds a tree on the rest, runs the combined policy for every candidate eta on
the held-out worlds and returns the eta with the fewest mean checks (ties go to the larger eta,
which relies less on the tree). The test worlds are never looked at.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from drd_planner.core.episode import TableOracle, run_episode
from drd_planner.core.policies import DEFAULT_ALPHA, DirectBisectPolicy
from drd_planner.core.problem import Problem
from drd_planner.core.tree import build_tree
from drd_planner.exceptions import ProblemError

#: Candidate thresholds; 1.0 means "switch at the root" (BiSECt with the training bias).
DEFAULT_ETA_CANDIDATES: tuple[float, ...] = (0.05, 0.1, 0.2, 0.4, 0.6, 1.0)
#: Fraction of the feasible training worlds held out for validation.
DEFAULT_VALIDATION_FRACTION = 0.1


@dataclass(frozen=True)
class SwitchThresholdChoice:
    """The chosen eta and the validation evidence behind it.

    Attributes:
        eta: the chosen threshold.
        mean_checks: candidate eta -> mean checks on the validation worlds.
        validation_ids: (k,) world rows held out (0-based rows of the problem's world database).
    """

    eta: float
    mean_checks: dict[float, float]
    validation_ids: tuple[int, ...]

    def as_json(self) -> dict[str, object]:
        """A JSON-able summary (for benchmark files and tree provenance)."""
        return {
            "eta": self.eta,
            "mean_checks": {f"{k:g}": v for k, v in sorted(self.mean_checks.items())},
            "num_validation_worlds": len(self.validation_ids),
        }


def select_switch_threshold(
    problem: Problem,
    *,
    candidates: Sequence[float] = DEFAULT_ETA_CANDIDATES,
    validation_fraction: float = DEFAULT_VALIDATION_FRACTION,
    seed: int = 0,
    alpha: float = DEFAULT_ALPHA,
    expand_threshold: float = 0.05,
    tree_options: Mapping[str, Any] | None = None,
) -> SwitchThresholdChoice:
    """Pick eta by validation on held-out feasible training worlds (see the module docstring).

    Args:
        problem: a problem with a world database; only its training worlds are used.
        candidates: thresholds to try, each in (0, 1].
        validation_fraction: share of the training worlds held out (at least one world).
        seed: seeds the hold-out draw.
        alpha: data weight of the leaf bias.
        expand_threshold: the tree's expansion threshold (as for the final tree).
        tree_options: further keyword arguments of :func:`drd_planner.core.tree.build_tree`
            (candidates, IncDRD, colouring), the same as for the final tree, so the validation
            tree is built the way the tree that will use eta is.

    Raises:
        ProblemError: no candidates, a candidate outside (0, 1], or no feasible training world.
    """
    cands = sorted({float(c) for c in candidates})
    if not cands or cands[0] <= 0.0 or cands[-1] > 1.0:
        raise ProblemError(f"eta candidates must be non-empty and lie in (0, 1]; got {list(candidates)}")
    if not 0.0 < validation_fraction < 1.0:
        raise ProblemError(f"validation_fraction must lie in (0, 1); got {validation_fraction}")
    worlds = problem.require_worlds()
    train = worlds.train_ids
    feasible = train[worlds.R[train].any(axis=1)]
    if feasible.size < 2:
        raise ProblemError("need at least two feasible training worlds to validate eta")
    k = min(feasible.size - 1, max(1, round(validation_fraction * train.size)))
    rng = np.random.default_rng(seed)
    held_out = np.sort(rng.choice(feasible, size=k, replace=False))
    fit = np.setdiff1d(train, held_out)
    sub = dataclasses.replace(problem, worlds=worlds.subset(fit, held_out))
    options = {k: v for k, v in (tree_options or {}).items() if k not in ("expand_threshold", "progress")}
    tree = build_tree(sub, expand_threshold=expand_threshold, progress=False, **options)
    costs = problem.edge_costs
    means: dict[float, float] = {}
    for eta in cands:
        total = 0
        for world in held_out:
            policy = DirectBisectPolicy(tree, problem.library, costs, eta=eta, alpha=alpha)
            result = run_episode(problem.library, costs, policy, TableOracle(worlds.X[world]))
            total += result.num_checks
        means[eta] = total / held_out.size
    best = min(means.values())
    eta = max(e for e, v in means.items() if v <= best + 1e-12)
    return SwitchThresholdChoice(eta, means, tuple(int(h) for h in held_out))
