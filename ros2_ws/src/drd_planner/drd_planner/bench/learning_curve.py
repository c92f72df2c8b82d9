"""Checks versus training-set size (the paper's Fig. 4): rebuild the tree on nested training subsets.

For each size s the first s worlds of one seeded permutation of the training ids are the training set
(so the subsets are nested), the DiRECt tree is rebuilt on them with :func:`core.tree.build_tree`, and
``direct_bisect``, ``direct_only`` and ``bisect`` run on the unchanged test worlds.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from drd_planner.arrays import FloatArray, IntArray
from drd_planner.bench.runner import DEFAULT_SETTINGS, PolicySettings, run_benchmark
from drd_planner.core.problem import Problem
from drd_planner.core.tree import build_tree
from drd_planner.exceptions import DrdError

#: Training-set sizes of the paper's Fig. 4 style curve (900 = every training world of the authors' split).
DEFAULT_SIZES = (50, 100, 200, 450, 900)
#: Policies the curve runs; ``direct_only``'s failure rate goes on the second axis.
CURVE_POLICIES = ("direct_bisect", "direct_only", "bisect")


@dataclass(frozen=True)
class TrainingCurve:
    """Mean checks and DiRECt-only failure rate per training-set size.

    Attributes:
        dataset: the problem's name.
        sizes: (k,) training-set sizes (worlds).
        mean_checks: policy name -> (k,) mean checks over the test worlds.
        failure_rate: (k,) fraction of test worlds on which ``direct_only`` failed.
        tree_nodes: (k,) nodes of each rebuilt tree.
        num_test: number of test worlds per point.
        seed: seed of the training-subset permutation.
    """

    dataset: str
    sizes: IntArray
    mean_checks: dict[str, FloatArray]
    failure_rate: FloatArray
    tree_nodes: IntArray
    num_test: int
    seed: int

    def as_json(self) -> dict[str, Any]:
        """JSON-safe dict of the curve."""
        return {
            "dataset": self.dataset,
            "sizes": self.sizes.tolist(),
            "mean_checks": {k: v.tolist() for k, v in self.mean_checks.items()},
            "direct_only_failure_rate": self.failure_rate.tolist(),
            "tree_nodes": self.tree_nodes.tolist(),
            "num_test": self.num_test,
            "seed": self.seed,
        }


def training_size_curve(
    problem: Problem,
    *,
    sizes: Sequence[int] = DEFAULT_SIZES,
    seed: int = 0,
    max_worlds: int | None = None,
    settings: PolicySettings = DEFAULT_SETTINGS,
    tree_options: Mapping[str, Any] | None = None,
) -> TrainingCurve:
    """Rebuild the tree on nested seeded training subsets and measure each policy on the test worlds.

    Args:
        problem: a problem with a world database.
        sizes: training-set sizes, each in [1, number of training worlds].
        seed: seed of the training-id permutation (and the episodes' base seed).
        max_worlds: only the first ``max_worlds`` test worlds.
        settings: eta, alpha and the leaf pseudo-count of the Bayesian policies.
        tree_options: keyword arguments for :func:`drd_planner.core.tree.build_tree`.

    Raises:
        DrdError: a size is out of range or no size is given.
    """
    worlds = problem.require_worlds()
    train = worlds.train_ids
    chosen = np.asarray(sorted(set(int(s) for s in sizes)), dtype=np.int64)
    if chosen.size == 0:
        raise DrdError("training-size curve needs at least one size")
    if chosen[0] < 1 or chosen[-1] > train.size:
        raise DrdError(f"training sizes must lie in [1, {train.size}] for {problem.name}, got {chosen.tolist()}")
    order = np.random.default_rng(seed).permutation(train)
    opts = dict(tree_options or {})
    checks: dict[str, list[float]] = {p: [] for p in CURVE_POLICIES}
    failures: list[float] = []
    nodes: list[int] = []
    num_test = 0
    for size in chosen.tolist():
        sub = dataclasses.replace(problem, worlds=worlds.subset(order[:size], worlds.test_ids))
        tree = build_tree(sub, progress=False, **opts)
        res = run_benchmark(
            sub,
            policies=CURVE_POLICIES,
            tree=tree,
            seed=seed,
            settings=settings,
            max_worlds=max_worlds,
            progress=False,
        )
        num_test = len(res.test_ids)
        for name in CURVE_POLICIES:
            checks[name].append(float(np.mean(res.policies[name].checks)))
        failures.append(res.policies["direct_only"].failures / max(num_test, 1))
        nodes.append(tree.num_nodes)
    return TrainingCurve(
        problem.name,
        chosen,
        {k: np.asarray(v, dtype=np.float64) for k, v in checks.items()},
        np.asarray(failures, dtype=np.float64),
        np.asarray(nodes, dtype=np.int64),
        num_test,
        seed,
    )
