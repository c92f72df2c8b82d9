#!/usr/bin/env python3
"""Region rules side by side: the paper's MaxProbReg against probability per expected check.

For every graph dataset of the authors (``../shared/data/gccd``, 100 test worlds each) this runs the
``drd bench`` pipeline once per rule (``drd_planner.core.region_rule``): the DiRECt tree built with the
rule, eta and kappa validated on held-out training worlds with that tree, then ``direct_bisect`` (whose
BiSECt stage follows the tree's rule), ``direct_bisect_fixed`` (the paper's eta 0.2 and fixed leaf) and
plain BiSECt with the rule (no tree). It prints mean checks per set, the oracle bound, and geometric means
of the ratios, and writes everything to ``--json``.

Usage:
  python scripts/experiments/bench_region_rule.py [--root ../shared/data/gccd] [--sets dataset_2d_6,...]
      [--max-worlds K] [--json out/region_rule.json]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from drd_planner.bench.runner import train_bias
from drd_planner.bench.suite import SuiteOptions, run_dataset
from drd_planner.core.episode import TableOracle, run_episode
from drd_planner.core.policies import BisectPolicy
from drd_planner.core.problem import Problem
from drd_planner.core.region_rule import REGION_RULES
from drd_planner.data.gccd import load_gccd_folder

POLICIES = ("direct_bisect", "direct_bisect_fixed")


def _bisect_mean(problem: Problem, rule: str, max_worlds: int | None) -> float:
    """Mean checks of plain BiSECt (training bias, MaxProbReg restriction by ``rule``) on the test worlds."""
    worlds = problem.require_worlds()
    theta = train_bias(problem)
    counts = []
    for world in worlds.test_ids[:max_worlds].tolist():
        policy = BisectPolicy(problem.library, theta, problem.edge_costs, region_rule=rule)
        result = run_episode(problem.library, problem.edge_costs, policy, TableOracle(worlds.X[world]))
        counts.append(len(result.checks))
    return float(np.mean(counts))


def run_set(folder: Path, max_worlds: int | None) -> dict[str, Any]:
    """Both rules on one dataset folder: mean checks per policy, the oracle bound, settings and seconds."""
    problem = load_gccd_folder(folder)
    row: dict[str, Any] = {"dataset": folder.name}
    for rule in REGION_RULES:
        t0 = time.perf_counter()
        options = SuiteOptions(policies=POLICIES, max_worlds=max_worlds, region_rules=(rule,))
        run = run_dataset(problem, options, progress=False)
        means = {name: float(np.mean(stats.checks)) for name, stats in run.result.policies.items()}
        means["bisect"] = _bisect_mean(problem, rule, max_worlds)
        row[rule] = {
            "mean_checks": means,
            "eta": run.result.settings.get("eta"),
            "pseudo_count": run.result.settings.get("pseudo_count"),
            "seconds": time.perf_counter() - t0,
        }
        row["oracle"] = float(np.nanmean(run.result.lower_bound))
    return row


def _geomean(values: list[float]) -> float:
    return float(np.exp(np.mean(np.log(values))))


def report(rows: list[dict[str, Any]]) -> str:
    """A markdown table of both rules per set and the geometric means of the ratios."""
    head = (
        "| dataset | oracle | direct_bisect (paper rule) | direct_bisect (per_check) | direct_bisect_fixed "
        "(paper) | bisect (paper rule) | bisect (per_check) |"
    )
    lines = [head, "|---|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        p, c = r["probability"]["mean_checks"], r["per_check"]["mean_checks"]
        lines.append(
            f"| {r['dataset']} | {r['oracle']:.2f} | {p['direct_bisect']:.2f} | {c['direct_bisect']:.2f} | "
            f"{p['direct_bisect_fixed']:.2f} | {p['bisect']:.2f} | {c['bisect']:.2f} |"
        )

    def ratio(a: tuple[str, str], b: tuple[str, str]) -> float:
        return _geomean([r[a[0]]["mean_checks"][a[1]] / r[b[0]]["mean_checks"][b[1]] for r in rows])

    def to_oracle(rule: str) -> float:
        return _geomean([r[rule]["mean_checks"]["direct_bisect"] / r["oracle"] for r in rows])

    lines += [
        "",
        f"geometric means over {len(rows)} sets:",
        f"  direct_bisect per_check / direct_bisect_fixed: "
        f"{ratio(('per_check', 'direct_bisect'), ('probability', 'direct_bisect_fixed')):.3f}",
        f"  direct_bisect paper rule / direct_bisect_fixed: "
        f"{ratio(('probability', 'direct_bisect'), ('probability', 'direct_bisect_fixed')):.3f}",
        f"  direct_bisect per_check / paper rule: "
        f"{ratio(('per_check', 'direct_bisect'), ('probability', 'direct_bisect')):.3f}",
        f"  bisect per_check / paper rule: {ratio(('per_check', 'bisect'), ('probability', 'bisect')):.3f}",
        f"  direct_bisect / oracle bound: paper rule {to_oracle('probability'):.3f}, "
        f"per_check {to_oracle('per_check'):.3f}",
    ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Run the comparison; 0 on success."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--root", type=Path, default=Path(__file__).resolve().parents[2] / "../shared/data/gccd")
    parser.add_argument("--sets", default="", help="comma-separated folder names (default: every graph set)")
    parser.add_argument("--max-worlds", type=int, default=None, help="first K test worlds per set")
    parser.add_argument("--json", type=Path, default=None, help="write the rows here")
    args = parser.parse_args(argv)
    names = [s for s in args.sets.split(",") if s] or sorted(
        p.name for p in args.root.iterdir() if (p / "graph.txt").is_file()
    )
    rows = []
    for name in names:
        t0 = time.perf_counter()
        rows.append(run_set(args.root / name, args.max_worlds))
        print(f"{name}: {time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)
    print(report(rows))
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(rows, indent=1) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
