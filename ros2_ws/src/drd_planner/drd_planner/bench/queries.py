"""The random-query benchmark (``drd bench --queries N``): every policy on N (start, goal) pairs.

Queries: the dataset's own first, then pairs drawn with a seeded generator: a start uniformly among the
vertices, and a goal uniformly among the vertices the start reaches in at least half of a sample of the
training worlds (so most queries have a free path, but not all). Query i runs against test world
i mod (number of test worlds).

Policies:
- every library policy (``direct_bisect``, ``bisect``, ``lazysp_set``, ...) through the same
  :class:`~drd_planner.planner.Planner`: the same online library (or the precomputed tree for the
  dataset's own query), the same graph fallback once the library is blocked;
- ``lazysp`` (and its selectors) on the whole graph, with the authors' 1000-check cap;
- ``check_all``: check every edge, then Dijkstra (its checks are E in every episode).

Per episode the fewest checks any planner needs knowing the world (:func:`certificate_size`); their mean is
``certificate_lower_bound``. Per policy: checks in episode order, failures (no verified path although the world has a
free one, or a budget ran out), ``false_no_path`` ("no path" although the world's graph has a free path: a
correctness error), mean overhead (library + selection) per episode, and the path cost over the
cheapest free graph path of that world. Every returned path is re-verified against the episode's own
check log.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import maximum_flow, shortest_path

from drd_planner.arrays import BoolArray, IntArray
from drd_planner.core.episode import TableOracle, run_episode, verify_path
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.lazysp import SELECTORS, GraphArcs, LazySP, LazySPSettings, lazysp_name
from drd_planner.core.problem import Problem
from drd_planner.exceptions import DrdError
from drd_planner.planner.planner import PLAN_POLICIES, Planner
from drd_planner.planner.query_library import ShortestPaths
from drd_planner.planner.result import PlanStage, PlanStatus
from drd_planner.progress import Progress

GRAPH_BASELINES = tuple(lazysp_name(s) for s in SELECTORS)
#: Policies of the query benchmark besides the library policies.
QUERY_ONLY_POLICIES = ("check_all",)
DEFAULT_QUERY_POLICIES = ("direct_bisect", "bisect", "lazysp_set", "lazysp", "check_all")


@dataclass
class QueryPolicyStats:
    """One policy's results over the query episodes."""

    checks: list[int] = field(default_factory=list)
    statuses: list[str] = field(default_factory=list)
    failures: int = 0
    false_no_path: int = 0
    overhead_ms: list[float] = field(default_factory=list)
    cost_ratio: list[float] = field(default_factory=list)
    stages: dict[str, int] = field(default_factory=dict)

    def as_json(self) -> dict[str, Any]:
        """The JSON entry of this policy."""
        checks = np.asarray(self.checks, dtype=np.float64)
        ratios = np.asarray(self.cost_ratio, dtype=np.float64)
        return {
            "checks": self.checks,
            "mean_checks": float(checks.mean()) if checks.size else None,
            "median_checks": float(np.median(checks)) if checks.size else None,
            "statuses": self.statuses,
            "failures": self.failures,
            "false_no_path": self.false_no_path,
            "mean_overhead_ms": float(np.mean(self.overhead_ms)) if self.overhead_ms else 0.0,
            "path_cost_ratio": float(ratios.mean()) if ratios.size else None,
            "stages": self.stages,
        }


def certificate_size(graph: ExplicitGraph, outcomes: BoolArray, start: int, goal: int) -> int:
    """The fewest checks any planner needs on this episode, knowing the world in advance.

    With a free path, every edge of the returned path must be checked: the fewest edges of a free path.
    Without one, "no path" needs checked blocked edges that cut start from goal: the minimum cut where
    blocked edges cost 1 and free ones cannot be cut (a max flow).
    """
    arcs = GraphArcs(graph)
    n = graph.num_vertices
    free = outcomes[arcs.edge]
    hops = sp.csr_array((np.ones(int(free.sum())), (arcs.u[free], arcs.v[free])), shape=(n, n))
    distance = shortest_path(hops, directed=True, unweighted=True, indices=start)[goal]
    if np.isfinite(distance):
        return int(distance)
    capacity = np.where(free, graph.num_edges + 1, 1).astype(np.int32)
    network = sp.csr_matrix((capacity, (arcs.u, arcs.v)), shape=(n, n))
    network.sum_duplicates()
    return int(maximum_flow(network, start, goal).flow_value)


def check_all_episode(graph: ExplicitGraph, outcomes: BoolArray, start: int, goal: int) -> tuple[int, IntArray | None]:
    """``check_all``: every edge checked, then the shortest free path (None when there is none)."""
    return graph.num_edges, ShortestPaths(GraphArcs(graph), graph.lengths).path(start, goal, outcomes)


def run_query_benchmark(
    problem: Problem,
    planner: Planner,
    queries: Sequence[tuple[int, int]],
    *,
    policies: Sequence[str] = DEFAULT_QUERY_POLICIES,
    seed: int = 0,
    max_checks: int | None = None,
    progress: bool | None = None,
) -> dict[str, Any]:
    """Run every policy on every query; the JSON document of ``drd bench --queries``."""
    known = set(PLAN_POLICIES) | set(GRAPH_BASELINES) | set(QUERY_ONLY_POLICIES)
    unknown = [p for p in policies if p not in known]
    if unknown:
        raise DrdError(f"unknown policies for --queries: {', '.join(unknown)}; known: {', '.join(sorted(known))}")
    graph = problem.graph
    worlds = problem.require_worlds()
    if graph is None or worlds.test_ids.size == 0:
        raise DrdError(f"{problem.name}: --queries needs the graph and at least one test world")
    truth_search = ShortestPaths(GraphArcs(graph), graph.lengths)
    episodes: list[dict[str, Any]] = []
    stats = {p: QueryPolicyStats() for p in policies}
    t0 = time.perf_counter()
    bar = Progress(len(queries) * len(policies), f"{problem.name} queries", unit="episode", enabled=progress)
    for i, (start, goal) in enumerate(queries):
        world = int(worlds.test_ids[i % worlds.test_ids.size])
        outcomes = worlds.X[world]
        best = truth_search.path(start, goal, outcomes)
        best_cost = None if best is None else float(graph.lengths[best].sum())
        episodes.append(
            {
                "world": world,
                "start": start,
                "goal": goal,
                "free_path": best is not None,
                "shortest_cost": best_cost,
                "certificate_checks": certificate_size(graph, outcomes, start, goal),
            }
        )
        for name in policies:
            found_edges, checks, status, overhead, stage = _episode(
                name, planner, graph, outcomes, start, goal, seed=seed + i, max_checks=max_checks
            )
            s = stats[name]
            s.checks.append(checks)
            s.statuses.append(status)
            s.overhead_ms.append(overhead)
            if stage:
                s.stages[stage] = s.stages.get(stage, 0) + 1
            if found_edges is not None:
                if best_cost and best_cost > 0:
                    s.cost_ratio.append(float(graph.lengths[found_edges].sum()) / best_cost)
            elif best is not None:
                s.failures += 1
                s.false_no_path += int(status == PlanStatus.NO_PATH.value)
            bar.update(1)
    bar.close()
    return {
        "dataset": problem.name,
        "queries": len(queries),
        "seed": seed,
        "settings": {
            "eta": planner.prior.eta,
            "pseudo_count": planner.prior.pseudo_count,
            "max_paths": planner.prior.max_paths,
            "max_checks": max_checks,
        },
        "episodes": episodes,
        "certificate_lower_bound": float(np.mean([e["certificate_checks"] for e in episodes])),
        "policies": {p: stats[p].as_json() for p in policies},
        "seconds": time.perf_counter() - t0,
    }


def _episode(
    name: str,
    planner: Planner,
    graph: ExplicitGraph,
    outcomes: BoolArray,
    start: int,
    goal: int,
    *,
    seed: int,
    max_checks: int | None,
) -> tuple[IntArray | None, int, str, float, str]:
    """(verified path or None, checks, status, overhead ms, stage) of one policy on one query."""
    if name == "check_all":
        checks, path = check_all_episode(graph, outcomes, start, goal)
        return path, checks, PlanStatus.FOUND.value if path is not None else PlanStatus.NO_PATH.value, 0.0, ""
    if name in GRAPH_BASELINES:
        selector = SELECTORS[GRAPH_BASELINES.index(name)]
        policy = LazySP(graph, start, goal, LazySPSettings(selector=selector, seed=seed))
        t0 = time.perf_counter()
        result = run_episode(None, planner.prior.edge_costs, policy, TableOracle(outcomes), max_checks=max_checks)
        spent = (time.perf_counter() - t0) * 1e3 - sum(c.check_ms for c in result.checks)
        return result.path_edges, result.num_checks, result.status.value, spent, "lazysp"
    plan = planner.plan(start, goal, TableOracle(outcomes), seed=seed, max_checks=max_checks, policy=name)
    edges = plan.edges if plan.found else None
    if edges is not None and edges.size:
        verify_path(edges, plan.outcomes())
    # Library policies share the planner's query cache; each is charged the library's build time.
    served = plan.status is not PlanStatus.REFUSED and plan.stage is not PlanStage.TRIVIAL
    build_s = planner.query_model(start, goal).build_s if served else 0.0
    overhead = (build_s + plan.timings.selection_s) * 1e3
    return edges, plan.num_checks, plan.status.value, overhead, plan.stage.value if plan.stage else ""


def query_markdown(doc: dict[str, Any]) -> str:
    """A markdown table of one query benchmark."""
    lines = [
        f"## {doc['dataset']}: {doc['queries']} random queries (seed {doc['seed']})",
        "",
        "| policy | mean checks | median | failures | false no-path | overhead ms | path cost ratio |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, s in doc["policies"].items():
        ratio = "-" if s["path_cost_ratio"] is None else f"{s['path_cost_ratio']:.3f}"
        lines.append(
            f"| {name} | {s['mean_checks']:.2f} | {s['median_checks']:.1f} | {s['failures']} | "
            f"{s['false_no_path']} | {s['mean_overhead_ms']:.2f} | {ratio} |"
        )
    free = sum(e["free_path"] for e in doc["episodes"])
    lines += ["", f"{free} of {len(doc['episodes'])} episodes have a free path in their test world.", ""]
    return "\n".join(lines)
