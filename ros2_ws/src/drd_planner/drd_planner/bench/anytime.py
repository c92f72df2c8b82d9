"""Anytime shorter paths (the paper's Q2) on a dataset's own query: path cost before and after improving.

For each test world that has a free start-goal path, the planner's default policy (``direct_bisect`` with
the dataset's DiRECt tree) plans to its first verified path (c checks); the same plan is then run with
``improve_budget`` = ``factor`` x c extra checks (:mod:`drd_planner.planner.anytime`), so factor 1 is a
total of 2c. A path's cost ratio is its length over the cheapest free graph path of that world
(Dijkstra over the world's full X row). Per factor the report gives the mean ratio before and after, the
gap reduction ((before - 1) - (after - 1)) / (before - 1) of those means, the extra checks used, how
many plans found a shorter path or the world's shortest one, and why the improvement stopped.

Every path is re-verified: the first path must be the one the budgeted plan records first, and every
returned path must have each edge checked free in the plan's own log and free in the world.
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from drd_planner.core.episode import TableOracle, verify_path
from drd_planner.core.lazysp import GraphArcs
from drd_planner.core.problem import Problem
from drd_planner.core.tree import build_tree
from drd_planner.exceptions import DrdError
from drd_planner.planner.anytime import DEFAULT_PATIENCE, ImproveBudget
from drd_planner.planner.planner import Planner
from drd_planner.planner.prior import QueryTree, WorldPrior, prior_from_problem
from drd_planner.planner.query_library import ShortestPaths
from drd_planner.progress import Progress

__all__ = ["AnytimeStats", "anytime_markdown", "anytime_prior", "run_anytime_benchmark"]

#: Extra checks as multiples of the first path's checks (1: the issue's "2x the first path's checks").
DEFAULT_FACTORS = (1.0,)


@dataclass
class AnytimeStats:
    """One budget factor's results over the test worlds with a free path (one entry per world)."""

    first_ratio: list[float] = field(default_factory=list)
    after_ratio: list[float] = field(default_factory=list)
    first_checks: list[int] = field(default_factory=list)
    extra_checks: list[int] = field(default_factory=list)
    improvements: list[int] = field(default_factory=list)
    stops: Counter[str] = field(default_factory=Counter)
    improve_ms: list[float] = field(default_factory=list)

    def as_json(self) -> dict[str, Any]:
        """The JSON entry of this factor (means over the worlds; None when there were none)."""
        before, after = _mean(self.first_ratio), _mean(self.after_ratio)
        gap = None
        if before is not None and after is not None and before > 1.0:
            gap = ((before - 1.0) - (after - 1.0)) / (before - 1.0)
        after_arr = np.asarray(self.after_ratio)
        return {
            "episodes": len(self.first_ratio),
            "first_cost_ratio": before,
            "after_cost_ratio": after,
            "gap_reduction": gap,
            "mean_first_checks": _mean(self.first_checks),
            "mean_extra_checks": _mean(self.extra_checks),
            "improved": int(sum(n > 0 for n in self.improvements)),
            "reached_shortest": int(np.sum(after_arr <= 1.0 + 1e-9)),
            "first_was_shortest": int(np.sum(np.asarray(self.first_ratio) <= 1.0 + 1e-9)),
            "stops": dict(sorted(self.stops.items())),
            "mean_improve_ms": _mean(self.improve_ms),
            "first_ratios": self.first_ratio,
            "after_ratios": self.after_ratio,
            "first_checks": self.first_checks,
            "extra_checks": self.extra_checks,
        }


def _mean(values: Sequence[float] | Sequence[int]) -> float | None:
    return float(np.mean(values)) if len(values) else None


def anytime_prior(problem: Problem, *, seed: int = 0) -> WorldPrior:
    """The prior of the problem's training worlds with its own DiRECt tree (default eta and kappa)."""
    from drd_planner.data.problem_source import problem_domain

    if problem.start is None or problem.goal is None:
        raise DrdError(f"{problem.name}: the anytime benchmark plans the dataset's own query; it has none")
    tree = build_tree(problem, progress=False)
    own = QueryTree(problem.name, int(problem.start), int(problem.goal), problem.library, tree)
    return prior_from_problem(problem, domain=problem_domain(problem), trees=(own,), library_seed=seed)


def run_anytime_benchmark(
    problem: Problem,
    planner: Planner,
    *,
    factors: Sequence[float] = DEFAULT_FACTORS,
    seed: int = 0,
    patience: int = DEFAULT_PATIENCE,
    progress: bool | None = None,
) -> dict[str, Any]:
    """First path, then the improvement with each budget factor, on every test world of the problem.

    Args:
        problem: a problem with a graph, its own query and test worlds.
        planner: plans it (:func:`anytime_prior` builds the usual one).
        factors: extra checks as multiples (> 0) of each world's first-path checks (at least 1 check).
        seed: world i (in test order) is planned with seed ``seed + i``.
        patience: the improvement's :attr:`ImproveBudget.patience`.
        progress: show a progress bar (None: only on a terminal).

    Returns:
        The JSON document: settings, counts of skipped worlds and one entry per factor.

    Raises:
        DrdError: no graph, query or test worlds, or a factor that is not positive.
    """
    worlds = problem.require_worlds()
    graph, start, goal = problem.graph, problem.start, problem.goal
    if graph is None or start is None or goal is None or worlds.test_ids.size == 0:
        raise DrdError(f"{problem.name}: the anytime benchmark needs a graph, a start and goal, and test worlds")
    if not factors or any(not (np.isfinite(f) and f > 0) for f in factors):
        raise DrdError(f"budget factors must be positive numbers, got {list(factors)}")
    truth = ShortestPaths(GraphArcs(graph), graph.lengths)
    stats = {float(f): AnytimeStats() for f in factors}
    no_free_path, first_failed = 0, 0
    t0 = time.perf_counter()
    bar = Progress(int(worlds.test_ids.size), f"{problem.name} anytime", unit="world", enabled=progress)
    for i, world in enumerate(worlds.test_ids.tolist()):
        bar.update(1)
        row = worlds.X[world]
        best = truth.path(start, goal, row)
        if best is None:
            no_free_path += 1
            continue
        shortest = float(graph.lengths[best].sum())
        first = planner.plan(start, goal, TableOracle(row), seed=seed + i)
        if not first.found:
            first_failed += 1
            continue
        for factor, s in stats.items():
            budget = ImproveBudget(checks=max(1, round(factor * first.num_checks)), patience=patience)
            result = planner.plan(start, goal, TableOracle(row), seed=seed + i, improve_budget=budget)
            _verify(result.edges, result.outcomes(), row, first.edges, result.improvements[0].path_edges)
            s.first_ratio.append(first.cost / shortest)
            s.after_ratio.append(result.cost / shortest)
            s.first_checks.append(first.num_checks)
            s.extra_checks.append(result.num_checks - first.num_checks)
            s.improvements.append(len(result.improvements) - 1)
            s.stops[result.improve_stop] += 1
            s.improve_ms.append((result.timings.total_s - result.improvements[0].elapsed_s) * 1e3)
    bar.close()
    return {
        "dataset": problem.name,
        "seed": seed,
        "test_worlds": int(worlds.test_ids.size),
        "no_free_path": no_free_path,
        "first_path_failed": first_failed,
        "settings": {
            "eta": planner.prior.eta,
            "pseudo_count": planner.prior.pseudo_count,
            "patience": patience,
        },
        "factors": {f"{f:g}": s.as_json() for f, s in stats.items()},
        "seconds": time.perf_counter() - t0,
    }


def _verify(
    edges: np.ndarray, outcomes: dict[int, bool], row: np.ndarray, first: np.ndarray, recorded: np.ndarray
) -> None:
    """Safety of one budgeted plan: its path checked free in its own log and free in the world."""
    verify_path(edges, outcomes)
    if not row[edges].all():
        raise DrdError("a returned path has an edge that is blocked in the world")
    if first.tolist() != recorded.tolist():
        raise DrdError("the budgeted plan's first path differs from the plain plan's (not deterministic)")


def anytime_markdown(docs: Sequence[dict[str, Any]]) -> str:
    """A markdown table of anytime benchmarks (one row per dataset and budget factor)."""
    lines = [
        "| dataset | extra budget | worlds | first-path cost ratio | after | gap reduction | first-path "
        "checks | extra checks used | improved | reached shortest | stops |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for doc in docs:
        for factor, s in doc["factors"].items():
            if not s["episodes"]:
                lines.append(f"| {doc['dataset']} | {factor}x | 0 | - | - | - | - | - | - | - | - |")
                continue
            gap = "-" if s["gap_reduction"] is None else f"{100 * s['gap_reduction']:.0f} %"
            stops = ", ".join(f"{k} {v}" for k, v in s["stops"].items())
            lines.append(
                f"| {doc['dataset']} | {factor}x | {s['episodes']} | {s['first_cost_ratio']:.3f} | "
                f"{s['after_cost_ratio']:.3f} | {gap} | {s['mean_first_checks']:.1f} | "
                f"{s['mean_extra_checks']:.1f} | {s['improved']} | {s['reached_shortest']} "
                f"(first: {s['first_was_shortest']}) | {stops} |"
            )
    return "\n".join(lines) + "\n"
