#!/usr/bin/env python3
"""The whole benchmark over every authors'-format dataset under a folder: Table 1, figures, timings.

Writes ``OUT/benchmark.json`` (one ``drd bench --json`` document per dataset, docs/getting-started.md,
with the Table-1 ``relative`` statistics), ``OUT/table1.md`` (the markdown report) and the figures under
``OUT/figures/``, and prints the total wall time. Same as
``drd bench --all GCCD --json OUT/benchmark.json --markdown OUT/table1.md --figures OUT/figures``: the
defaults, i.e. eta, the posterior leaf's kappa and the region rule validated per dataset;
``--paper-leaf`` keeps the paper's fixed leaf bias and region rule (only eta validated:
``drd bench --kappa none --region-rule probability``).

Usage: python scripts/experiments/full_benchmark.py [--gccd ../shared/data/gccd] [--out results] [--max-worlds K]
[--paper-leaf]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

from drd_planner.bench.runner import DEFAULT_POLICIES, json_safe
from drd_planner.bench.suite import SuiteOptions, costs_figure, run_suite, suite_json, suite_markdown
from drd_planner.core.region_rule import DEFAULT_REGION_RULE
from drd_planner.exceptions import DrdError

REPO = Path(__file__).resolve().parents[2]
SHARED = Path(os.environ.get("DRD_SHARED_DATA", REPO.parent / "shared" / "data"))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--gccd", default=str(SHARED / "gccd"), help="folder holding the dataset folders")
    parser.add_argument("--out", default=str(REPO / "results"), help="output folder (gitignored)")
    parser.add_argument("--max-worlds", type=int, default=None, help="only the first K test worlds")
    parser.add_argument("--policies", default=",".join(DEFAULT_POLICIES))
    parser.add_argument("--no-figures", action="store_true")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--paper-leaf",
        action="store_true",
        help="the paper's fixed leaf bias and region rule, only eta validated (default: eta, kappa and the "
        "region rule validated, as drd bench does)",
    )
    args = parser.parse_args()
    out = Path(args.out)
    paper: dict[str, Any] = (
        {"pseudo_counts": (None,), "region_rules": (DEFAULT_REGION_RULE,)} if args.paper_leaf else {}
    )
    options = SuiteOptions(
        policies=tuple(p.strip() for p in args.policies.split(",") if p.strip()),
        seed=args.seed,
        max_worlds=args.max_worlds,
        figures=None if args.no_figures else out / "figures",
        **paper,
    )
    t0 = time.perf_counter()
    try:
        suite = run_suite(args.gccd, options, progress=True)
        figures = costs_figure(suite.runs, options)
    except DrdError as exc:
        print(f"full_benchmark: error: {exc}", file=sys.stderr)
        return 2
    out.mkdir(parents=True, exist_ok=True)
    doc = json_safe(suite_json(suite, options, figures=figures))
    (out / "benchmark.json").write_text(json.dumps(doc, indent=1, allow_nan=False))
    report = suite_markdown(suite, options)
    (out / "table1.md").write_text(report)
    print(report)
    for run in suite.runs:
        per_policy = ", ".join(f"{k} {v.episode_seconds:.1f}" for k, v in run.result.policies.items())
        print(f"{run.result.dataset}: {run.seconds:.1f} s ({per_policy})")
    print(
        f"wrote {out / 'benchmark.json'}, {out / 'table1.md'} and "
        f"{len(figures) + sum(len(r.figures) for r in suite.runs)} figure files"
    )
    print(f"total wall time {time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
