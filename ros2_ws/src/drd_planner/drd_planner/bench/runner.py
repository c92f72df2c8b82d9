"""Run policies over a problem's test worlds against a table-lookup oracle and collect statistics.

The JSON written by :func:`benchmark_json` follows DESIGN.md section 5:
``{"dataset", "test_ids", "oracle_lower_bound": {"mean", "per_world"}, "policies": {NAME:
{"mean_checks", "median_checks", "checks", "failures", "mean_select_ms"}}}`` plus a ``tree`` block.
``test_ids`` are 0-based row indices of the dataset's world matrix.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from tqdm import tqdm

from drd_planner.core.bisect import bias_from_worlds
from drd_planner.core.bounds import oracle_lower_bound
from drd_planner.core.episode import TableOracle, run_episode
from drd_planner.core.policies import DEFAULT_ALPHA, DEFAULT_ETA, POLICIES, TREE_POLICIES, PolicyContext
from drd_planner.core.problem import Problem
from drd_planner.core.tree import DecisionTree, build_tree
from drd_planner.exceptions import DrdError

#: Policies ``drd bench`` runs when none are named.
DEFAULT_POLICIES = ("direct_bisect", "direct_only", "bisect", "bisect_all")


@dataclass(frozen=True)
class PolicyStats:
    """Per-policy results over the test worlds (in test-id order)."""

    checks: list[int]
    failures: int
    select_ms: list[float]
    episode_seconds: float

    def as_json(self) -> dict[str, Any]:
        """The DESIGN.md section 5 policy block."""
        arr = np.asarray(self.checks, dtype=np.float64)
        return {
            "mean_checks": float(arr.mean()) if arr.size else float("nan"),
            "median_checks": float(np.median(arr)) if arr.size else float("nan"),
            "checks": [int(c) for c in self.checks],
            "failures": int(self.failures),
            "mean_select_ms": float(np.mean(self.select_ms)) if self.select_ms else 0.0,
        }


@dataclass(frozen=True)
class BenchmarkResult:
    """Everything one benchmark run measured."""

    dataset: str
    test_ids: list[int]
    lower_bound: list[float]
    policies: dict[str, PolicyStats]
    tree_info: dict[str, Any] = field(default_factory=dict)


def run_benchmark(
    problem: Problem,
    *,
    policies: Sequence[str] = DEFAULT_POLICIES,
    tree: DecisionTree | None = None,
    seed: int = 0,
    eta: float = DEFAULT_ETA,
    alpha: float = DEFAULT_ALPHA,
    max_worlds: int | None = None,
    progress: bool | None = None,
) -> BenchmarkResult:
    """Run each policy once per test world (seeded per world) and collect the check counts.

    Args:
        problem: a problem with a world database (train ids train, test ids are the episodes).
        policies: registry names (see ``drd_planner.core.policies.POLICIES``).
        tree: a prebuilt tree; built from the training worlds when a tree policy needs one.
        seed: base seed; world k of the test list uses ``seed + k``.
        eta: switch threshold of ``direct_bisect``.
        alpha: data weight of the bias.
        max_worlds: only the first ``max_worlds`` test worlds (smoke runs).
        progress: show progress bars (None: only on a terminal).
    """
    unknown = [p for p in policies if p not in POLICIES]
    if unknown:
        raise DrdError(f"unknown policy {', '.join(unknown)}; known: {', '.join(sorted(POLICIES))}")
    worlds = problem.require_worlds()
    test_ids = worlds.test_ids if max_worlds is None else worlds.test_ids[:max_worlds]
    tree_info: dict[str, Any] = {}
    if tree is None and any(p in TREE_POLICIES for p in policies):
        tree = build_tree(problem, progress=progress)
    if tree is not None:
        tree_info = {"nodes": tree.num_nodes, "depth": tree.depth(), **tree.info}
    train = worlds.train_ids
    theta = bias_from_worlds(worlds.X[train], worlds.weights(train), alpha=alpha)
    path_costs = problem.library.path_costs(problem.edge_costs)
    lower = oracle_lower_bound(worlds.R[test_ids], path_costs)
    results: dict[str, PolicyStats] = {}
    for name in policies:
        checks: list[int] = []
        select_ms: list[float] = []
        failures = 0
        t0 = time.perf_counter()
        for k, world in enumerate(tqdm(test_ids, desc=name, unit="world", disable=_disable(progress))):
            ctx = PolicyContext(problem.library, problem.edge_costs, theta, tree, seed + k, eta, alpha)
            policy = POLICIES[name](ctx)
            result = run_episode(problem.library, problem.edge_costs, policy, TableOracle(worlds.X[world]))
            checks.append(result.num_checks)
            select_ms.extend(c.select_ms for c in result.checks)
            failures += int(not result.success)
        results[name] = PolicyStats(checks, failures, select_ms, time.perf_counter() - t0)
    return BenchmarkResult(problem.name, [int(t) for t in test_ids], lower.tolist(), results, tree_info)


def _disable(progress: bool | None) -> bool | None:
    return None if progress is None else not progress


def benchmark_json(result: BenchmarkResult) -> dict[str, Any]:
    """The JSON document of DESIGN.md section 5."""
    lb = np.asarray(result.lower_bound, dtype=np.float64)
    return {
        "dataset": result.dataset,
        "test_ids": result.test_ids,
        "oracle_lower_bound": {
            "mean": nanmean_or_nan(lb),
            "per_world": [None if np.isnan(v) else float(v) for v in lb],
        },
        "policies": {name: stats.as_json() for name, stats in result.policies.items()},
        "tree": result.tree_info,
    }


def markdown_table(results: Sequence[BenchmarkResult], policies: Sequence[str]) -> str:
    """One row per dataset: mean checks per policy (failures in brackets) and the oracle bound."""
    head = "| dataset | " + " | ".join(policies) + " | oracle bound |"
    rule = "|---|" + "---|" * (len(policies) + 1)
    rows = [head, rule]
    for res in results:
        cells = []
        for name in policies:
            stats = res.policies.get(name)
            if stats is None:
                cells.append("—")
                continue
            mean = float(np.mean(stats.checks)) if stats.checks else float("nan")
            cells.append(f"{mean:.2f}" + (f" ({stats.failures} failed)" if stats.failures else ""))
        lb = nanmean_or_nan(np.asarray(res.lower_bound, dtype=np.float64))
        rows.append(f"| {res.dataset} | " + " | ".join(cells) + f" | {lb:.2f} |")
    return "\n".join(rows) + "\n"


def nanmean_or_nan(values: np.ndarray) -> float:
    """Mean of the finite entries; NaN (without a warning) when there are none."""
    finite = values[np.isfinite(values)]
    return float(finite.mean()) if finite.size else float("nan")
