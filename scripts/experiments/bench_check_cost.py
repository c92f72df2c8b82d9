#!/usr/bin/env python3
"""Time to a verified plan at stated check costs on the shipped priors, held-out worlds, three query kinds.

For each shipped prior (``trees/NAME.npz``) it draws **held-out** worlds from the prior's own world model
(``domain.make_world(model, seed)`` with small seeds ``--world-seed``, ``--world-seed + 1``, ...; the
training worlds' seeds are the 63-bit ``SeedSequence`` seeds of ``drd_planner.data.seeding``, so none is
reused), keeping those where the prior's stored query has a free path (as the datasets' test splits do),
and times, at each check cost C (ms of CPU busy-waited per check inside the oracle, on top of the live FCL
checker):

- ``stored``: the prior's precomputed query, once per world;
- ``new``: random vertex pairs (start uniform, goal among the vertices the start reaches in at least half
  of 200 training worlds, ``--reach``), each with a free path in its world;
- ``off_graph``: random states that are not graph vertices, start and goal (uniform in the box of the
  vertex states, heading included; kept when the state itself is free in the world, the Planner can join
  it and the query has a free path), planned through the Planner's public API, which joins them;

with ``direct_bisect`` and ``bisect`` (``Planner.plan``, the check cost unknown to it), ``direct_bisect_lead``
(``direct_bisect`` with the planner told C: a new query's lead, ``drd_planner.planner.lead``), ``lazysp`` and
``check_all`` on the query's
graph (``drd_planner.bench.cost_episodes``), and OMPL's LazyPRM on the prior's graph with the same live
checker and the same per-check cost in its worker (vertex queries only: its roadmap cannot join an off-graph
state). Query i runs against world i mod W. Times are CPU ms of the process that plans (the OMPL worker's
own for LazyPRM); medians over the queries of a kind that every method verified at every C. With ``--repeat R``
every episode (OMPL's too) runs R times and keeps the run of median CPU time.

Usage: python scripts/experiments/bench_check_cost.py [--priors heli_wires,heli_terrain,heli_lines,arm_table_clutter]
    [--costs 0,0.2,1,5] [--worlds 4] [--new 8] [--off-graph 8] [--seed 0] [--world-seed 0] [--no-ompl]
    [--repeat 1] [--json FILE] [--markdown FILE]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from drd_planner.bench.check_cost import Timed, cost_key, parse_check_costs
from drd_planner.bench.cost_bench import (
    CostRun,
    cost_markdown,
    episode_records,
    median_episode,
    run_cost_episodes,
    summarize_costs,
)
from drd_planner.bench.cost_episodes import LEAD_POLICY, CostQuery, EpisodeTime
from drd_planner.bench.held_out import WORLD_MODELS, held_out_worlds, new_queries, off_graph_queries
from drd_planner.bench.ompl_peer import LiveWorlds, ompl_available, run_ompl_lazyprm_live
from drd_planner.bench.world_recipes import WorldRecipe
from drd_planner.domains.base import domain_from_spec
from drd_planner.planner.planner import Planner
from drd_planner.planner.prior import WorldPrior
from drd_planner.planner.prior_file import load_prior

REPO = Path(__file__).resolve().parents[2]
POLICIES = ("direct_bisect", LEAD_POLICY, "bisect", "lazysp", "check_all")


def ompl_episodes(
    prior: WorldPrior, queries: list[CostQuery], recipes: list[WorldRecipe], costs: tuple[float, ...], repeat: int
) -> list[EpisodeTime]:
    """LazyPRM on every vertex query (one worker per (start, goal) and run: its worlds and costs)."""
    by_pair: dict[tuple[int, int], list[int]] = {}
    for i, q in enumerate(queries):
        if q.kind != "off_graph":
            by_pair.setdefault((int(q.start), int(q.goal)), []).append(i)  # type: ignore[arg-type]
    runs: dict[tuple[int, float], list[EpisodeTime]] = {}
    for (start, goal), indices in by_pair.items():
        live = LiveWorlds(prior.domain, dict(prior.domain_spec), tuple(recipes[queries[i].world] for i in indices))
        for _ in range(repeat):
            result = run_ompl_lazyprm_live(prior.graph, start, goal, live, check_costs_ms=costs)
            blocks = iter(result["worlds"])
            for i in indices:
                for cost in costs:
                    b = next(blocks)
                    spent = Timed(1e3 * float(b["cpu_s"]), 1e3 * float(b["wall_s"]))
                    episode = EpisodeTime(
                        "ompl_lazyprm", i, queries[i].kind, cost, bool(b["success"]), int(b["checks"]), spent
                    )
                    runs.setdefault((i, cost), []).append(episode)
    return [median_episode(r) for r in runs.values()]


def run_prior(name: str, args: argparse.Namespace, costs: tuple[float, ...], ompl: bool) -> dict[str, Any]:
    """Every method on one prior's held-out queries; its summary and markdown."""
    t0 = time.perf_counter()
    prior = load_prior(REPO / "trees" / f"{name}.npz")
    domain = domain_from_spec(prior.domain, prior.domain_spec)
    model = WORLD_MODELS[name]
    recipes, worlds, rows = held_out_worlds(domain, prior, model, args.worlds, args.world_seed)
    print(f"{name}: worlds {[r.label for r in recipes]} ({time.perf_counter() - t0:.0f} s)", file=sys.stderr)
    rng = np.random.default_rng(args.seed)
    planner = Planner(prior)
    stored = prior.trees[0]
    queries = [CostQuery("stored", stored.start, stored.goal, w) for w in range(len(worlds))]
    queries += new_queries(prior, rows, args.new, rng, args.reach)
    queries += off_graph_queries(planner, domain, worlds, rows, args.off_graph, rng)
    kinds = {k: sum(q.kind == k for q in queries) for k in ("stored", "new", "off_graph")}
    print(f"{name}: queries {kinds} ({time.perf_counter() - t0:.0f} s)", file=sys.stderr)

    def oracle_of(world: int) -> Any:
        return domain.checker(worlds[world])

    run = CostRun(policies=POLICIES, seed=args.seed, repeat=args.repeat)
    episodes = run_cost_episodes(planner, queries, oracle_of, costs, run, rows=rows)
    if ompl:
        episodes += ompl_episodes(prior, queries, recipes, costs, args.repeat)
    summary = summarize_costs(episodes, costs)
    notes = [
        f"held-out worlds of the {model!r} model, seeds {[r.seed for r in recipes]}; queries {kinds}",
        "check_all: the world's E edges checked once (batched) and charged to each query, plus E x C ms",
    ]
    if ompl:
        notes.append("ompl_lazyprm: vertex queries only (its roadmap is the prior's graph); CPU of its worker")
    title = f"{name}: time to a verified plan (median CPU ms)"
    print(f"{name}: done ({time.perf_counter() - t0:.0f} s)", file=sys.stderr)
    return {
        "summary": summary,
        "markdown": cost_markdown(summary, costs, title=title, notes=notes),
        "queries": kinds,
        "episodes": episode_records(episodes),
        "worlds": [r.to_json() for r in recipes],
        "seconds": time.perf_counter() - t0,
    }


def ratio_lines(results: dict[str, Any], costs: tuple[float, ...], policy: str = "direct_bisect") -> list[str]:
    """The 'done when' check: ``policy`` / lazysp median CPU per prior, kind and C; in brackets the median of the
    per-query ratios (each query against itself)."""
    lines = [
        "| prior | kind | " + " | ".join(f"C = {cost_key(c)}" for c in costs) + " |",
        "|" + "---|" * (len(costs) + 2),
    ]
    for name, res in results.items():
        s = res["summary"]
        for kind in ("stored", "new", "off_graph"):
            cells = []
            for c in costs:
                a = s[policy]["time_ms"][cost_key(c)]["kinds"].get(kind)
                b = s["lazysp"]["time_ms"][cost_key(c)]["kinds"].get(kind)
                paired = s[policy]["paired_to_lazysp"].get(cost_key(c), {}).get(kind)
                ok = a and b and a["median"] is not None and b["median"]
                cell = f"{a['median'] / b['median']:.2f}" if ok else "-"
                cells.append(cell + (f" ({paired['median']:.2f})" if paired else ""))
            lines.append(f"| {name} | {kind} | " + " | ".join(cells) + " |")
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--priors", default=",".join(WORLD_MODELS), help="comma-separated shipped priors")
    parser.add_argument("--costs", default="0,0.2,1,5", help="ms of CPU per check, comma-separated")
    parser.add_argument("--worlds", type=int, default=4, help="held-out worlds per prior")
    parser.add_argument("--new", type=int, default=8, help="random vertex-pair queries per prior")
    parser.add_argument("--off-graph", type=int, default=8, help="random off-graph queries per prior")
    parser.add_argument("--seed", type=int, default=0, help="seed of the queries and the policies")
    parser.add_argument("--reach", type=float, default=0.5, help="new queries: training fraction connected")
    parser.add_argument("--world-seed", type=int, default=0, help="first world seed (held out: see above)")
    parser.add_argument("--no-ompl", action="store_true", help="skip ompl_lazyprm")
    parser.add_argument(
        "--repeat", type=int, default=1, help="runs of each episode (OMPL's too), the run of median CPU time kept"
    )
    parser.add_argument("--json", type=Path, default=None)
    parser.add_argument("--markdown", type=Path, default=None)
    args = parser.parse_args(argv)
    costs = parse_check_costs(args.costs)
    if args.repeat < 1:
        parser.error(f"--repeat must be at least 1, got {args.repeat}")
    names = [n.strip() for n in args.priors.split(",") if n.strip()]
    unknown = [n for n in names if n not in WORLD_MODELS]
    if unknown:
        parser.error(f"unknown priors {unknown}; known: {', '.join(WORLD_MODELS)}")
    ompl = not args.no_ompl and ompl_available()[0]
    if not args.no_ompl and not ompl:
        print(ompl_available()[1], file=sys.stderr)
    results = {name: run_prior(name, args, costs, ompl) for name in names}
    text = "\n".join(r["markdown"] for r in results.values())
    for policy in ("direct_bisect", LEAD_POLICY):
        text += f"\n## {policy} / lazysp, median CPU ms to a verified plan (per query, the median ratio)\n\n"
        text += "\n".join(ratio_lines(results, costs, policy)) + "\n"
    text += "\n"
    print(text)
    if args.markdown:
        args.markdown.write_text(text)
    if args.json:
        doc = {
            "costs_ms": [cost_key(c) for c in costs],
            "args": {k: str(v) for k, v in vars(args).items()},
            "priors": {n: {k: v for k, v in r.items() if k != "markdown"} for n, r in results.items()},
        }
        args.json.write_text(
            json.dumps(doc, indent=1, default=lambda x: None if isinstance(x, float) and math.isnan(x) else x)
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
