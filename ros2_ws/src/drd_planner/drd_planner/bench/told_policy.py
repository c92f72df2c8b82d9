"""``direct_bisect`` *told* a group of worlds: what the greedy method needs with a perfect prior.

The known-worlds bound (:mod:`drd_planner.bench.known_worlds`) is the best *any* policy can do when it is
told that the world is one of a group ``G``. Running ``direct_bisect`` with ``G`` itself as its database
(the tree grown down to single worlds, the leaf bias learnt from ``G``) is one such policy, so its mean
over ``G`` is an *upper* bound on that optimum; against the exact optimum on the same groups it measures
how far the greedy choices are from optimal, and told all the test worlds it shows what the method would
need if its prior were exactly the test set (the best a prior could be), whatever the training data.

The database holds the group twice (training rows, then the same worlds as test rows) so that the
runner's world database keeps training and test rows apart; the duplicated rows only double every
world's weight, which changes no probability.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray
from drd_planner.bench.runner import PolicySettings, run_world, train_bias
from drd_planner.core.problem import Problem
from drd_planner.core.region_rule import REGION_RULES
from drd_planner.core.tree import build_tree
from drd_planner.core.worlds import WorldDatabase
from drd_planner.exceptions import ProblemError

__all__ = ["TOLD_SETTINGS", "TOLD_THRESHOLD", "told_checks"]

#: Expansion threshold of the told tree: below one world of a group of up to 1000, so the tree is grown
#: until it has told every world apart (or no check splits the rest).
TOLD_THRESHOLD = 1e-3
#: The settings tried: eta 1e-4 follows the tree to its end, eta 1 is BiSECt from the root; each with the
#: fixed leaf and the posterior leaf (kappa 5).
TOLD_SETTINGS = tuple(
    PolicySettings(eta=eta, pseudo_count=kappa) for eta in (1e-4, 0.05, 0.2, 1.0) for kappa in (None, 5.0)
)


def told_checks(
    problem: Problem,
    group: npt.ArrayLike,
    region_rule: str,
    settings: tuple[PolicySettings, ...] = TOLD_SETTINGS,
) -> FloatArray:
    """Checks of ``direct_bisect`` told ``group`` on each of its worlds, for each setting.

    Args:
        problem: a problem with worlds (its library, edge costs and X are used).
        group: (g,) world rows of ``problem``'s X.
        region_rule: the tree's and BiSECt's region rule (one of ``REGION_RULES``).
        settings: the eta / kappa settings to run.

    Returns:
        (len(settings), g) the cost of each episode (same unit as the edge costs).
    """
    if region_rule not in REGION_RULES:
        raise ProblemError(f"unknown region rule {region_rule!r}; valid: {', '.join(REGION_RULES)}")
    worlds = problem.require_worlds()
    ids = np.asarray(group, dtype=np.int64).ravel()
    if ids.size == 0 or ids.min() < 0 or ids.max() >= worlds.num_worlds:
        raise ProblemError(f"group must hold world rows in [0, {worlds.num_worlds})")
    k = ids.size
    told = WorldDatabase(
        np.concatenate([worlds.X[ids]] * 2),
        np.concatenate([worlds.R[ids]] * 2),
        np.arange(k),
        np.arange(k, 2 * k),
    )
    sub = dataclasses.replace(problem, worlds=told)
    tree = build_tree(sub, progress=False, expand_threshold=TOLD_THRESHOLD, region_rule=region_rule)
    theta = train_bias(sub)
    return np.array(
        [
            [
                run_world(sub, "direct_bisect", k + j, theta=theta, tree=tree, seed=j, settings=st).total_cost(
                    problem.edge_costs
                )
                for j in range(k)
            ]
            for st in settings
        ]
    )
