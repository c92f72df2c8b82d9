#!/usr/bin/env python3
"""Does a DiRECt tree grown online beat BiSECt on the queries a robot asks? A script that reports.

    python scripts/experiments/bench_online_tree.py [--priors heli_wires,heli_lines,arm_table_clutter] [--worlds 6]
        [--queries 4] [--etas 1,0.4,0.2] [--seed 7] [--json FILE] [--markdown FILE]

For each shipped prior (``trees/<name>.npz``) it draws ``--worlds`` **held-out** worlds from the prior's own
world model (seeds 10_000 + seed * 100 + i; the training worlds were drawn from 63-bit seeds of a
``SeedSequence``), checks every edge of each with the real checker once (the table the episodes read, so the
CPU times below are the planner's own: library, tree, selection, bookkeeping), and asks the queries a robot
asks, each with a free path in its world:

- **long**: a start vertex and a goal among the 10 % of the vertices its world's free paths reach that are
  farthest from it (a query across the map);
- **replan**: the same goal from the vertices a quarter, half and three quarters along the long query's first
  verified path (the robot flying the route asks again from where it is).

Each query is planned by one :class:`~drd_planner.Planner` per eta of ``--etas`` (``Planner.set_leaf``, the
prior's kappa and region rule): eta 1 is BiSECt from the first check (no online tree is built: what every
shipped prior's validation chose for new queries), eta < 1 grows a DiRECt tree online for the query and
leaves it for BiSECt when the consistent worlds fall to eta. Per prior, kind and eta: episodes with a free
path, mean and median checks, and median CPU ms per plan (``time.process_time``; a new query's library and
tree built inside). Every found path is re-verified against the world's table.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from drd_planner import Planner, TableOracle
from drd_planner.planner import load_prior
from drd_planner.planning.prior_domain import rebuild_domain

ROOT = Path(__file__).resolve().parents[2]
#: The world model each shipped prior was built with (``trees/README.md``).
WORLD_MODELS = {"heli_wires": "wires", "heli_lines": "corridors", "arm_table_clutter": "table_clutter"}
KINDS = ("long", "replan")
#: Where along the long query's path the replans start (fractions of its vertices).
REPLAN_AT = (0.25, 0.5, 0.75)


@dataclass
class Cell:
    """The episodes of one (prior, kind, eta)."""

    checks: list[int] = field(default_factory=list)
    cpu_s: list[float] = field(default_factory=list)
    no_path: int = 0

    def row(self) -> dict[str, Any]:
        """The JSON of this cell."""
        return {
            "found": len(self.checks),
            "no_path": self.no_path,
            "checks_mean": float(np.mean(self.checks)) if self.checks else None,
            "checks_median": float(np.median(self.checks)) if self.checks else None,
            "cpu_ms_median": 1e3 * float(np.median(self.cpu_s)) if self.cpu_s else None,
        }


def _adjacency(graph: Any, free: np.ndarray) -> sp.csr_matrix:
    """(V, V) lengths (m or rad) of the ``free`` (E,) edges of the prior's graph, both ways when undirected."""
    u, v = graph.edges[free, 0], graph.edges[free, 1]
    n = graph.num_vertices
    matrix = sp.csr_matrix((graph.lengths[free], (u, v)), shape=(n, n))
    return matrix if graph.directed else (matrix + matrix.T).tocsr()


def _far_goal(matrix: sp.csr_matrix, rng: np.random.Generator) -> tuple[int, int]:
    """A start vertex and a goal among the 10 % of vertices a free path reaches that are farthest from it."""
    while True:
        start = int(rng.integers(matrix.shape[0]))
        dist = dijkstra(matrix, indices=start)
        reach = np.flatnonzero(np.isfinite(dist) & (dist > 0))
        if reach.size >= 20:
            far = reach[dist[reach] >= np.quantile(dist[reach], 0.9)]
            return start, int(rng.choice(far))


def _plan(planner: Planner, start: int, goal: int, table: np.ndarray, cell: Cell) -> list[int] | None:
    """Plan one episode into ``cell``; the path's vertices (None without a path)."""
    oracle = TableOracle(table)
    t0 = time.process_time()
    result = planner.plan(start, goal, oracle)
    cpu = time.process_time() - t0
    if not result.found:
        cell.no_path += 1
        return None
    assert all(bool(table[e]) for e in result.edges), "a found path with a blocked edge"
    cell.checks.append(result.num_checks)
    cell.cpu_s.append(cpu)
    return [int(v) for v in result.vertices]


def run_prior(name: str, args: argparse.Namespace) -> dict[str, Any]:
    """Every kind and eta of one prior."""
    prior = load_prior(ROOT / "trees" / f"{name}.npz")
    domain = rebuild_domain(prior, name)
    graph = prior.graph
    rng = np.random.default_rng(args.seed)
    planners = {}
    for eta in args.etas:
        planner = Planner(prior)
        planner.set_leaf(eta, prior.pseudo_count, region_rule=prior.region_rule)
        planners[eta] = planner
    cells = {kind: {eta: Cell() for eta in args.etas} for kind in KINDS}
    t_check = time.perf_counter()
    for w in range(args.worlds):
        world = domain.make_world(WORLD_MODELS[name], 10_000 + args.seed * 100 + w)
        table = np.asarray(domain.checker(world).check_many(np.arange(graph.num_edges)), dtype=bool)
        matrix = _adjacency(graph, table)
        for _ in range(args.queries):
            start, goal = _far_goal(matrix, rng)
            routes = {eta: _plan(planners[eta], start, goal, table, cells["long"][eta]) for eta in args.etas}
            route = routes[1.0] if 1.0 in routes else next(iter(routes.values()))
            if route is None or len(route) < 4:
                continue
            for frac in REPLAN_AT:
                here = route[int(frac * (len(route) - 1))]
                if here == goal:
                    continue
                for eta in args.etas:
                    _plan(planners[eta], here, goal, table, cells["replan"][eta])
        print(f"{name}: world {w + 1}/{args.worlds} done", file=sys.stderr, flush=True)
    return {
        "prior": name,
        "world_model": WORLD_MODELS[name],
        "validated_eta_new_queries": prior.eta,
        "seconds": time.perf_counter() - t_check,
        "cells": {kind: {f"{eta:g}": c.row() for eta, c in by.items()} for kind, by in cells.items()},
    }


def markdown(results: list[dict[str, Any]]) -> str:
    """One row per prior, kind and eta."""
    lines = [
        "| prior | queries | eta | found | no path | checks mean | checks median | CPU ms median |",
        "|---|---|---:|---:|---:|---:|---:|---:|",
    ]
    for res in results:
        for kind, by in res["cells"].items():
            for eta, row in by.items():
                mean, med, cpu = row["checks_mean"], row["checks_median"], row["cpu_ms_median"]
                lines.append(
                    f"| {res['prior']} | {kind} | {eta} | {row['found']} | {row['no_path']} | "
                    f"{'-' if mean is None else f'{mean:.2f}'} | {'-' if med is None else f'{med:.0f}'} | "
                    f"{'-' if cpu is None else f'{cpu:.1f}'} |"
                )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    """Run the report and print (and write) its table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--priors", default="heli_wires,heli_lines,arm_table_clutter")
    parser.add_argument("--worlds", type=int, default=6, help="held-out worlds per prior")
    parser.add_argument("--queries", type=int, default=4, help="long queries per world")
    parser.add_argument("--etas", default="1,0.4,0.2", help="switch thresholds, comma-separated")
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--json", type=Path)
    parser.add_argument("--markdown", type=Path)
    args = parser.parse_args(argv)
    args.etas = [float(x) for x in args.etas.split(",")]
    results = [run_prior(name, args) for name in args.priors.split(",")]
    table = markdown(results)
    print(table)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"seed": args.seed, "results": results}, indent=1))
    if args.markdown:
        args.markdown.parent.mkdir(parents=True, exist_ok=True)
        args.markdown.write_text(table)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
