"""Time to a verified plan with a live edge checker: ``direct_bisect``, ``lazysp`` and ``ompl_lazyprm``.

Each run plans one (start, goal) query on one world with a fresh checker of one collision model and measures
the wall time from the call to the verified path, collision checks included:

- ``direct_bisect``: :meth:`~drd_planner.planner.Planner.plan` with the prior's tree (graph fallback
  included);
- ``lazysp``: LazySP (forward selector) on the whole graph through the episode runner;
- ``ompl_lazyprm``: OMPL's LazyPRM on the same graph in its worker process, its motion validator answering
  from the same kind of live checker (:func:`~drd_planner.bench.ompl_peer.run_ompl_lazyprm_live`).

A run counts as **verified** only when every edge of its path was checked free in that run by that checker
(from the run's own log of checks), whatever the planner says.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from drd_planner.bench.ompl_peer import LiveWorlds, run_ompl_lazyprm_live
from drd_planner.core.episode import run_episode
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.lazysp import LazySP, LazySPSettings
from drd_planner.domains.base import EdgeChecker
from drd_planner.planner.planner import Planner

__all__ = [
    "METHODS",
    "PlanRun",
    "RecordingOracle",
    "summarize_plans",
    "time_lazysp",
    "time_ompl",
    "time_planner",
]

#: The methods timed, in report order.
METHODS: tuple[str, ...] = ("direct_bisect", "lazysp", "ompl_lazyprm")


@dataclass(frozen=True)
class PlanRun:
    """One timed plan.

    Attributes:
        method: one of :data:`METHODS`.
        model: the collision model (``spheres`` or ``meshes``).
        world: the world's label.
        found: the planner returned a path.
        verified: every edge of that path was checked free in this run.
        checks: edges checked.
        seconds: wall time of the plan, checks included (s).
        check_seconds: time inside the checker (s).
        path_edges: the path's edge ids (empty when none).
    """

    method: str
    model: str
    world: str
    found: bool
    verified: bool
    checks: int
    seconds: float
    check_seconds: float
    path_edges: list[int] = field(default_factory=list)


class RecordingOracle:
    """An edge oracle that answers with ``checker`` and records every answer and the time it took.

    Args:
        checker: the live edge checker.
    """

    def __init__(self, checker: EdgeChecker) -> None:
        self.checker = checker
        self.log: dict[int, bool] = {}
        self.seconds = 0.0

    def check(self, edge: int) -> bool:
        """The checker's answer for ``edge`` (recorded)."""
        t0 = time.perf_counter()
        free = bool(self.checker.check(edge))
        self.seconds += time.perf_counter() - t0
        self.log[int(edge)] = free
        return free


def checked_free(path_edges: Sequence[int], log: dict[int, bool]) -> bool:
    """Whether a non-empty path's every edge is in ``log`` as free."""
    return len(path_edges) > 0 and all(log.get(int(e)) is True for e in path_edges)


def time_planner(
    planner: Planner, checker: EdgeChecker, query: tuple[int, int], *, model: str, world: str, seed: int = 0
) -> PlanRun:
    """Time ``direct_bisect`` through :meth:`Planner.plan` for ``query`` (start, goal vertex ids)."""
    oracle = RecordingOracle(checker)
    t0 = time.perf_counter()
    result = planner.plan(query[0], query[1], oracle, seed=seed, policy="direct_bisect")
    seconds = time.perf_counter() - t0
    edges = result.edges.tolist() if result.found else []
    return PlanRun(
        "direct_bisect",
        model,
        world,
        result.found,
        result.found and checked_free(edges, oracle.log),
        len(oracle.log),
        seconds,
        oracle.seconds,
        edges,
    )


def time_lazysp(
    graph: ExplicitGraph, checker: EdgeChecker, query: tuple[int, int], *, model: str, world: str
) -> PlanRun:
    """Time LazySP (forward selector, no check budget) on ``graph`` for ``query`` (start, goal)."""
    oracle = RecordingOracle(checker)
    t0 = time.perf_counter()
    policy = LazySP(graph, query[0], query[1], LazySPSettings(max_checks=None))
    episode = run_episode(None, graph.lengths, policy, oracle)
    seconds = time.perf_counter() - t0
    found = episode.success and episode.path_edges is not None
    edges = [int(e) for e in episode.path_edges] if found and episode.path_edges is not None else []
    return PlanRun(
        "lazysp",
        model,
        world,
        found,
        found and checked_free(edges, oracle.log),
        len(oracle.log),
        seconds,
        oracle.seconds,
        edges,
    )


def time_ompl(
    graph: ExplicitGraph, query: tuple[int, int], live: LiveWorlds, *, model: str, time_limit_s: float = 60.0
) -> list[PlanRun]:
    """Time OMPL's LazyPRM on every world of ``live`` (one worker process), answered by live checkers."""
    result = run_ompl_lazyprm_live(graph, query[0], query[1], live, time_limit_s=time_limit_s)
    runs = []
    for block in result["worlds"]:
        log = dict(zip(block["checked_edges"], block["checked_free"], strict=True))
        edges = [int(e) for e in block["path_edges"]]
        runs.append(
            PlanRun(
                "ompl_lazyprm",
                model,
                str(block["label"]),
                bool(block["ompl_solved"]),
                bool(block["success"]) and checked_free(edges, log),
                int(block["checks"]),
                float(block["wall_s"]),
                float(block["check_s"]),
                edges,
            )
        )
    return runs


def merge_repeats(runs: Sequence[PlanRun]) -> list[PlanRun]:
    """One run per (method, model, world): the best (least) time of its repeats, verified only if all were.

    Repeats make the same checks (the planners and checkers are deterministic), so they differ only by what
    else the machine did meanwhile; the least time is the one least disturbed (as ``timeit`` reports).
    """
    groups: dict[tuple[str, str, str], list[PlanRun]] = {}
    for r in runs:
        groups.setdefault((r.method, r.model, r.world), []).append(r)
    return [
        replace(
            group[0],
            found=all(r.found for r in group),
            verified=all(r.verified for r in group),
            seconds=min(r.seconds for r in group),
            check_seconds=min(r.check_seconds for r in group),
        )
        for group in groups.values()
    ]


def _model_block(chosen: list[PlanRun], every: list[PlanRun]) -> dict[str, Any]:
    """Counts over ``every`` run of one model, times and checks over the ``chosen`` (both verified) ones."""

    def mean(values: list[float]) -> float:
        return float(np.mean(values)) if values else float("nan")

    return {
        "verified": sum(r.verified for r in every),
        "found": sum(r.found for r in every),
        "ms_mean": 1e3 * mean([r.seconds for r in chosen]),
        "ms_median": 1e3 * float(np.median([r.seconds for r in chosen])) if chosen else float("nan"),
        "check_ms_mean": 1e3 * mean([r.check_seconds for r in chosen]),
        "checks_mean": mean([float(r.checks) for r in chosen]),
    }


def summarize_plans(runs: Sequence[PlanRun], models: tuple[str, str] = ("spheres", "meshes")) -> dict[str, Any]:
    """Per method: per model the verified plans, mean and median time and checks, and the time ratios.

    Repeats are merged first (:func:`merge_repeats`). Times and checks are taken over the worlds where **both**
    models verified a plan, so the ratios compare the same worlds: ``ratio`` is the second model's mean time
    over the first's, ``ratio_median`` the median over those worlds of the per-world ratio.

    Returns:
        ``{method: {"worlds", "both_verified", model: {"verified", "found", "ms_mean", "ms_median",
        "check_ms_mean", "checks_mean"}, "ratio", "ratio_median"}}``.
    """
    merged = merge_repeats(runs)
    out: dict[str, Any] = {}
    for method in METHODS:
        by_model = {m: {r.world: r for r in merged if r.method == method and r.model == m} for m in models}
        worlds = sorted(set(by_model[models[0]]) | set(by_model[models[1]]))
        if not worlds:
            continue
        both = [w for w in worlds if all(w in by_model[m] and by_model[m][w].verified for m in models)]
        block: dict[str, Any] = {"worlds": len(worlds), "both_verified": len(both)}
        for m in models:
            block[m] = _model_block([by_model[m][w] for w in both], list(by_model[m].values()))
        first, second = block[models[0]]["ms_mean"], block[models[1]]["ms_mean"]
        block["ratio"] = second / first if first > 0 else float("nan")
        per_world = [by_model[models[1]][w].seconds / by_model[models[0]][w].seconds for w in both]
        block["ratio_median"] = float(np.median(per_world)) if per_world else float("nan")
        out[method] = block
    return out
