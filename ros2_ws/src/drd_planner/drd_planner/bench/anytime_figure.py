"""The checks-versus-path-cost figure of ``drd bench --figures``: what more checks buy in path length.

On the test worlds of a dataset's own query that have a free path, each point is (mean checks, mean path
cost ratio), the cost ratio being the verified path's length over the world's cheapest free graph path:

* ``direct_bisect`` + anytime: the first verified path (the planner's default policy on the dataset's prior,
  :func:`~drd_planner.bench.anytime.anytime_prior`), then the anytime improvement
  (:mod:`~drd_planner.planner.anytime`) with extra checks of 0.5, 1, 2 and 3 times the first path's, a curve;
* every full-graph LazySP policy of the run (``lazysp``, ``lazysp_posterior``, ...), one point each: they
  verify the shortest free path, so their ratio is 1 and their cost is in checks.

Only episodes on worlds with a free path count, the same worlds for every point.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from drd_planner.bench.anytime import anytime_prior, run_anytime_benchmark
from drd_planner.bench.runner import (
    DEFAULT_SETTINGS,
    BenchmarkResult,
    PolicySettings,
    run_world,
    train_bias,
)
from drd_planner.core.lazysp import GraphArcs
from drd_planner.core.policies import graph_policies
from drd_planner.core.problem import Problem
from drd_planner.exceptions import DrdError
from drd_planner.planner import Planner
from drd_planner.planner.query_library import ShortestPaths

__all__ = ["ANYTIME_FACTORS", "checks_vs_cost", "plot_checks_vs_cost"]

#: Extra checks of the anytime curve, as multiples of each world's first-path checks.
ANYTIME_FACTORS: tuple[float, ...] = (0.5, 1.0, 2.0, 3.0)


def checks_vs_cost(
    problem: Problem,
    result: BenchmarkResult,
    *,
    seed: int = 0,
    settings: PolicySettings | None = None,
    factors: Sequence[float] = ANYTIME_FACTORS,
) -> dict[str, Any]:
    """The figure's data: the anytime curve and one point per full-graph policy of ``result``.

    Returns:
        ``{"anytime": [(checks, ratio), ...] (first path first), "policies": {name: (checks, ratio)},
        "worlds": n}``, means over the ``n`` test worlds with a free path.

    Raises:
        DrdError: the problem has no graph or own query (the anytime plan needs them).
    """
    worlds = problem.require_worlds()
    run = dataclasses.replace(  # the run's test worlds only (``--max-worlds``)
        problem, worlds=worlds.subset(worlds.train_ids, np.asarray(result.test_ids, dtype=np.int64))
    )
    doc = run_anytime_benchmark(run, Planner(anytime_prior(run, seed=seed)), factors=factors, seed=seed, progress=False)
    entries = list(doc["factors"].values())
    if not entries or not entries[0]["episodes"]:
        raise DrdError(f"{problem.name}: no test world with a free path and a first plan to draw")
    first = entries[0]
    curve = [(float(first["mean_first_checks"]), float(first["first_cost_ratio"]))]
    curve += [
        (float(e["mean_first_checks"]) + float(e["mean_extra_checks"]), float(e["after_cost_ratio"])) for e in entries
    ]
    points = _graph_policy_points(problem, result, seed=seed, settings=settings)
    return {"anytime": curve, "policies": points, "worlds": int(first["episodes"])}


def _graph_policy_points(
    problem: Problem, result: BenchmarkResult, *, seed: int, settings: PolicySettings | None
) -> dict[str, tuple[float, float]]:
    """(mean checks, mean cost ratio) of each full-graph policy of the run, on worlds with a free path."""
    graph, worlds = problem.graph, problem.require_worlds()
    assert graph is not None and problem.start is not None and problem.goal is not None
    truth = ShortestPaths(GraphArcs(graph), graph.lengths)
    theta = train_bias(problem)
    points: dict[str, tuple[float, float]] = {}
    for name in (n for n in result.policies if n in graph_policies() and n.startswith("lazysp")):
        checks, ratios = [], []
        for k, world in enumerate(result.test_ids):
            best = truth.path(problem.start, problem.goal, worlds.X[world])
            if best is None:
                continue
            episode = run_world(
                problem,
                name,
                world,
                theta=theta,
                tree=None,
                seed=seed + k,
                settings=dataclasses.replace(settings or DEFAULT_SETTINGS, imitation_model=result.imitation_model),
            )
            if episode.path_edges is None:
                continue
            checks.append(episode.num_checks)
            ratios.append(float(graph.lengths[episode.path_edges].sum() / graph.lengths[best].sum()))
        if checks:
            points[name] = (float(np.mean(checks)), float(np.mean(ratios)))
    return points


def plot_checks_vs_cost(data: dict[str, Any], name: str, out: str | Path) -> list[Path]:
    """Draw :func:`checks_vs_cost`'s data; write PNG and SVG next to ``out``."""
    from matplotlib.figure import Figure

    from drd_planner.bench.plots import save_figure

    fig = Figure(figsize=(6.4, 4.2))
    ax = fig.subplots()
    xs, ys = zip(*data["anytime"], strict=True)
    ax.plot(xs, ys, "-o", color="#1f4fd8", label="direct_bisect, then anytime (0.5-3x extra checks)")
    ax.plot(xs[0], ys[0], "s", color="#1f4fd8", markersize=9, label="direct_bisect: first verified path")
    for policy, (x, y) in sorted(data["policies"].items()):
        ax.plot(x, y, "^", markersize=8, label=policy)
    ax.axhline(1.0, color="#888888", linewidth=0.8, linestyle=":")
    ax.set_xscale("log")
    ax.set_xlabel("checks (mean over test worlds, log scale)")
    ax.set_ylabel("path cost / cheapest free path (mean)")
    ax.set_title(f"{name}: checks versus path cost ({data['worlds']} worlds with a free path)", fontsize=10)
    ax.legend(fontsize=7, loc="upper right")
    return save_figure(fig, out)
