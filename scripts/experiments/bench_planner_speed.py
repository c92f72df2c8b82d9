"""How fast the Planner serves a new query, a repeated one, and each selection; memory of prior and caches.

    python scripts/experiments/bench_planner_speed.py [--gccd DIR] [--queries 20] [--seed 0] [--json FILE]

Default data: the authors' largest graph here, SE(2) Bugtrap (``dataset_xyh_5``: 3 049 vertices, 7 981
edges), with **all 1 000 worlds** as the prior (n = 1000) and m = 500. For each of ``--queries`` random
(start, goal) pairs it measures, on one test world:

- *new query*: building the library (and its lazy DiRECt tree) plus the first selection, with eta forced
  below 1 so that the first selection is a DiRECt step at the root (the expensive case);
- *repeated query*: the same query again (cache hit): the whole call with one check, less the check;
- *selection per step*: every later selection of the plan (tree steps and BiSECt steps alike);

and reports medians and 90th percentiles, next to the targets (200 ms, 2 ms, 0.5 ms). Ratios are taken in
one run on one machine; absolute times move with the machine's load.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import tracemalloc
from pathlib import Path

import numpy as np

from drd_planner import Planner, TableOracle, prior_from_problem
from drd_planner.core.worlds import WorldDatabase
from drd_planner.data.gccd import load_gccd_folder

DEFAULT = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "gccd" / "dataset_xyh_5"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--gccd", type=Path, default=DEFAULT)
    parser.add_argument("--queries", type=int, default=20)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--eta", type=float, default=0.2, help="switch threshold (below 1: DiRECt at the root)")
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()

    problem = load_gccd_folder(args.gccd)
    worlds = problem.require_worlds()
    everything = np.arange(worlds.num_worlds)
    test_world = int(worlds.test_ids[0])
    tracemalloc.start()
    full = dataclasses.replace(
        problem, worlds=WorldDatabase(worlds.X, worlds.R, everything, np.zeros(0, dtype=np.int64))
    )
    prior = prior_from_problem(full, domain="gccd", eta=args.eta, max_paths=500)
    prior_bytes = tracemalloc.get_traced_memory()[0]
    planner = Planner(prior, cache_size=args.queries + 1)
    rng = np.random.default_rng(args.seed)
    n = prior.graph.num_vertices
    new_ms, repeat_ms, step_ms, checks, libs = (
        list[float](),
        list[float](),
        list[float](),
        list[int](),
        list[int](),
    )
    oracle_row = worlds.X[test_world]
    while len(new_ms) < args.queries:
        s, g = (int(v) for v in rng.integers(n, size=2))
        if s == g:
            continue
        first = planner.plan(s, g, TableOracle(oracle_row), seed=0, max_checks=1)
        if first.library_size == 0:
            continue  # no training world connects them: the graph stage, not what is measured here
        t = first.timings
        new_ms.append((planner.query_model(s, g).build_s + t.selection_s) * 1e3)
        libs.append(first.library_size)
        again = planner.plan(s, g, TableOracle(oracle_row), seed=0, max_checks=1)
        repeat_ms.append((again.timings.total_s - again.timings.checks_s) * 1e3)  # everything but the check
        whole = planner.plan(s, g, TableOracle(oracle_row), seed=0)
        step_ms.extend(c.select_ms for c in whole.checks[1:] if c.stage in ("tree", "bisect"))
        checks.append(whole.num_checks)
    cache_bytes = tracemalloc.get_traced_memory()[0] - prior_bytes
    tracemalloc.stop()

    def row(name: str, values: list[float], target: float) -> dict[str, float]:
        arr = np.asarray(values)
        out = {
            "median_ms": float(np.median(arr)),
            "p90_ms": float(np.percentile(arr, 90)),
            "target_ms": target,
        }
        print(f"{name:22s} median {out['median_ms']:8.3f} ms   p90 {out['p90_ms']:8.3f} ms   target {target:g} ms")
        return out

    print(
        f"{args.gccd.name}: {n} vertices, {prior.graph.num_edges} edges, prior of {prior.num_worlds} worlds, "
        f"m <= {prior.max_paths} (median library {int(np.median(libs))} paths), eta {args.eta}, "
        f"{args.queries} queries"
    )
    doc = {
        "dataset": args.gccd.name,
        "worlds": prior.num_worlds,
        "edges": prior.graph.num_edges,
        "new_query": row("new query (lib+sel)", new_ms, 200.0),
        "repeated_query": row("repeated query", repeat_ms, 2.0),
        "selection_step": row("selection per step", step_ms, 0.5),
        "mean_checks": float(np.mean(checks)),
        "memory": {
            "prior_mib": prior_bytes / 2**20,
            "query_caches_mib": cache_bytes / 2**20,
            "per_query_mib": cache_bytes / 2**20 / args.queries,
            "planner_estimate": planner.memory_bytes(),
        },
    }
    mem = doc["memory"]
    print(
        f"memory: prior {mem['prior_mib']:.1f} MiB; {args.queries} cached queries {mem['query_caches_mib']:.1f} MiB "
        f"({mem['per_query_mib']:.2f} MiB each)"
    )
    if args.json:
        args.json.write_text(json.dumps(doc, indent=1))
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
