#!/usr/bin/env python3
"""How many checks no policy can avoid: the known-worlds bound on the authors' datasets.

The oracle bound charges each test world its cheapest valid library path and nothing for finding it.
This script splits the 100 test worlds of every authors' graph set into groups of g (a seeded shuffle)
and solves exactly, per group, the best any policy can do when it is told the world is one of the
group's (``drd_planner.bench.known_worlds``). The mean over the groups bounds every policy's mean
checks over the test worlds from below; g = 1 is the oracle bound, and the bound grows with g towards
what the Bayes-optimal policy for these very worlds would need.

``--told`` sizes run ``direct_bisect`` *told* each group (``drd_planner.bench.told_policy``): its database
(tree, leaf bias) is the group's worlds themselves, with every setting of ``TOLD_SETTINGS`` and both region
rules (the lowest mean is shown). With the same groups as the bound this measures how far the greedy
method is from the optimum on the same knowledge; told all 100 test worlds, how far a perfect prior would
bring it.

With ``--bench`` (a ``drd bench`` JSON, e.g. ``results/benchmark.json`` from
``scripts/experiments/full_benchmark.py``) it sets the policies' mean checks on the same test worlds beside it.

Usage:
  python scripts/experiments/search_bound.py [--root ../shared/data/gccd] [--sets dataset_2d_1,...]
      [--group-sizes 1,5,10] [--told 10,100] [--node-budget N] [--bench results/benchmark.json]
      [--policies direct_bisect,bisect] [--json out/search_bound.json] [--markdown out/search_bound.md]
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

from drd_planner.bench.known_worlds import DEFAULT_NODE_BUDGET, known_worlds_bound
from drd_planner.bench.suite import discover_datasets
from drd_planner.bench.told_policy import TOLD_SETTINGS, told_checks
from drd_planner.core.region_rule import REGION_RULES
from drd_planner.data.gccd import load_gccd_folder
from drd_planner.exceptions import ProblemError
from drd_planner.settings import shared_data_dir


def bound_set(folder: Path, group_sizes: list[int], told: list[int], seed: int, node_budget: int) -> dict[str, Any]:
    """The bound for each group size on one dataset's test worlds (None where the search gave up) and
    the told direct_bisect's mean checks for each ``told`` size (same shuffle)."""
    problem = load_gccd_folder(folder)
    worlds = problem.require_worlds()
    test = np.asarray(worlds.test_ids)
    feasible = test[problem.library.valid_paths(worlds.X[test]).any(axis=1)]
    path_costs = problem.library.path_costs(problem.edge_costs)
    oracle = [float(path_costs[worlds.R[w]].min()) for w in feasible.tolist()]
    row: dict[str, Any] = {
        "dataset": folder.name,
        "test_ids": test.tolist(),
        "worlds": int(feasible.size),
        "oracle": float(np.mean(oracle)),
    }
    row["bounds"], row["seconds"] = {}, {}
    for g in group_sizes:
        t0 = time.perf_counter()
        try:
            b = known_worlds_bound(
                worlds.X,
                problem.library,
                problem.edge_costs,
                feasible,
                group_size=g,
                seed=seed,
                node_budget=node_budget,
            )
        except ProblemError as exc:
            print(f"  {folder.name} g={g}: {exc}", file=sys.stderr, flush=True)
            row["bounds"][str(g)] = None
        else:
            row["bounds"][str(g)] = b.mean
        row["seconds"][str(g)] = time.perf_counter() - t0
        print(
            f"  {folder.name} g={g}: {row['bounds'][str(g)]} ({row['seconds'][str(g)]:.0f} s)",
            file=sys.stderr,
            flush=True,
        )
    row["told"] = {}
    order = np.random.default_rng(seed).permutation(feasible)
    for g in told:
        groups = np.array_split(order, math.ceil(order.size / g))
        means: dict[str, float] = {}
        for rule in REGION_RULES:
            per_group = [told_checks(problem, grp, rule) for grp in groups]
            for i, st in enumerate(TOLD_SETTINGS):
                label = f"{rule} eta {st.eta:g} kappa {st.pseudo_count}"
                means[label] = float(np.mean([c for checks in per_group for c in checks[i]]))
        row["told"][str(g)] = means
        print(f"  {folder.name} told {g}: {means}", file=sys.stderr, flush=True)
    return row


def policy_means(bench: Path, policies: list[str]) -> dict[str, dict[str, Any]]:
    """Per dataset: test ids and the policies' mean checks from a ``drd bench`` JSON."""
    doc = json.loads(bench.read_text())
    out: dict[str, dict[str, Any]] = {}
    for entry in doc.get("datasets", []):
        stats = entry.get("policies", {})
        out[entry["dataset"]] = {
            "test_ids": entry.get("test_ids"),
            "means": {p: stats[p]["mean_checks"] for p in policies if p in stats},
        }
    return out


def _values(row: dict[str, Any], bench: dict[str, dict[str, Any]], policies: list[str]) -> dict[str, float | None]:
    """One dataset's columns: oracle, bound per group size, told (the lower of the two rules), policies."""
    values: dict[str, float | None] = {"oracle": row["oracle"]}
    values.update({f"bound g={g}": b for g, b in row["bounds"].items()})
    solved = [b for b in row["bounds"].values() if b is not None]
    values["best bound"] = max(solved) if solved else None  # every one is a lower bound: so is the largest
    values.update({f"told g={g}": min(means.values()) for g, means in row["told"].items()})
    entry = bench.get(row["dataset"], {})
    same_worlds = entry.get("test_ids") in (None, row["test_ids"])  # another test split is not comparable
    for p in policies:
        values[p] = entry.get("means", {}).get(p) if same_worlds else None
    return values


def _geomean_ratio(table: list[dict[str, float | None]], top: str, bottom: str) -> str:
    """Geometric mean of top / bottom over the sets with both, and how many."""
    pairs = [(v[top], v[bottom]) for v in table if v.get(top) is not None and v.get(bottom) is not None]
    logs = [math.log(t / b) for t, b in pairs if t is not None and b is not None]
    return f"{math.exp(sum(logs) / len(logs)):.3f} ({len(logs)} sets)" if logs else "- (no set)"


def report(
    rows: list[dict[str, Any]],
    group_sizes: list[int],
    told: list[int],
    bench: dict[str, dict[str, Any]],
    policies: list[str],
) -> str:
    """A markdown table (oracle, bound per group size, told direct_bisect, policies) and ratio means."""
    table = [_values(r, bench, policies) for r in rows]
    columns = [
        "oracle",
        *(f"bound g={g}" for g in group_sizes),
        "best bound",
        *(f"told g={g}" for g in told),
        *policies,
    ]
    out = ["| dataset | " + " | ".join(columns) + " |", "|---|" + "---:|" * len(columns)]
    for r, v in zip(rows, table, strict=True):
        cells = ["-" if v.get(c) is None else f"{v[c]:.2f}" for c in columns]
        out.append(f"| {r['dataset']} | " + " | ".join(cells) + " |")
    out += ["", "Geometric means over the sets:"]
    for g in group_sizes:
        out.append(f"- bound with groups of {g} / oracle bound: {_geomean_ratio(table, f'bound g={g}', 'oracle')}")
    for g in told:
        out.append(
            f"- direct_bisect told groups of {g} / oracle bound: {_geomean_ratio(table, f'told g={g}', 'oracle')}"
        )
        if g in group_sizes:
            ratio = _geomean_ratio(table, f"told g={g}", f"bound g={g}")
            out.append(f"- direct_bisect told groups of {g} / their exact optimum: {ratio}")
    top = f"bound g={max(group_sizes)}"
    for p in policies:
        out.append(
            f"- {p} / oracle bound: {_geomean_ratio(table, p, 'oracle')}; / {top}: {_geomean_ratio(table, p, top)}"
        )
    return "\n".join(out) + "\n"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        "--root", default=str(shared_data_dir() / "gccd"), help="folder of the authors' dataset folders"
    )
    parser.add_argument("--sets", default="", help="comma-separated folder names (default: every graph set)")
    parser.add_argument("--group-sizes", default="1,5,10", help="comma-separated group sizes")
    parser.add_argument("--told", default="10,100", help="group sizes for the told direct_bisect ('' for none)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the shuffle that forms the groups")
    parser.add_argument("--node-budget", type=int, default=DEFAULT_NODE_BUDGET, help="search nodes per group")
    parser.add_argument("--bench", default=None, help="a drd bench JSON with the policies' checks")
    parser.add_argument("--policies", default="direct_bisect,direct_bisect_fixed,bisect")
    parser.add_argument("--json", default=None, help="write the numbers here")
    parser.add_argument("--markdown", default=None, help="write the table here")
    parser.add_argument("--report", default=None, help="only print the table of an earlier --json file")
    args = parser.parse_args()
    sizes = sorted({int(g) for g in args.group_sizes.split(",") if g})
    if not sizes or sizes[0] < 1:
        parser.error("--group-sizes needs positive integers")
    told = sorted({int(g) for g in args.told.split(",") if g})
    root = Path(args.root)
    names = [s for s in args.sets.split(",") if s] or [f.name for f in discover_datasets(root)[0]]
    policies = [p for p in args.policies.split(",") if p] if args.bench else []
    bench = policy_means(Path(args.bench), policies) if args.bench else {}
    rows: list[dict[str, Any]] = json.loads(Path(args.report).read_text()) if args.report else []
    for name in [] if args.report else names:
        try:
            rows.append(bound_set(root / name, sizes, told, args.seed, args.node_budget))
        except Exception as exc:  # a folder without X or test worlds: say so, go on
            print(f"skipped {name}: {exc}", file=sys.stderr)
    text = report(rows, sizes, told, bench, policies)
    print(text, end="")
    for path, content in ((args.json, json.dumps(rows, indent=1)), (args.markdown, text)):
        if path:
            Path(path).parent.mkdir(parents=True, exist_ok=True)
            Path(path).write_text(content)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
