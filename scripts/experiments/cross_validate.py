#!/usr/bin/env python3
"""K-fold cross-validation of the combined method against BiSECt on dataset files (low-noise comparison).

The held-back test split of a dataset (10 %) is small, so a difference of a check or two between
policies is within its noise. This script tests every feasible world once (``drd_planner.bench.
cross_validation``): per fold the tree, the validated switch threshold and the bias come from all other
worlds. It prints, per dataset, the mean and median checks of each policy, the oracle bound and the
paired difference to the reference policy with a 95 % bootstrap interval.

Usage:
  python scripts/experiments/cross_validate.py datasets/heli_wires.npz [more.npz ...] [--folds 10]
      [--policies direct_bisect,bisect] [--reference bisect] [--seed 0] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from drd_planner.bench.cross_validation import cross_validate
from drd_planner.bench.runner import check_policy_names
from drd_planner.data.dataset_file import load_dataset_problem
from drd_planner.exceptions import DrdError


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("datasets", nargs="+", type=Path, help="dataset files written by drd build-dataset")
    parser.add_argument("--folds", type=int, default=10)
    parser.add_argument("--policies", default="direct_bisect,bisect")
    parser.add_argument("--reference", default="bisect", help="policy the others are paired against")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", type=Path, default=None, help="write the summaries here")
    args = parser.parse_args(argv)
    policies = tuple(p.strip() for p in args.policies.split(",") if p.strip())
    try:
        check_policy_names(policies)
        if args.reference not in policies:
            raise DrdError(f"--reference {args.reference} must be one of --policies")
        summaries = []
        print(f"| dataset | worlds | {' | '.join(policies)} | oracle bound | paired difference to {args.reference} |")
        print(f"|---|---:|{'---:|' * len(policies)}---:|---|")
        for path in args.datasets:
            t0 = time.perf_counter()
            problem = load_dataset_problem(path)
            result = cross_validate(problem, policies=policies, folds=args.folds, seed=args.seed)
            summary = result.as_json(args.reference)
            summary["seconds"] = time.perf_counter() - t0
            summaries.append(summary)
            cells = [f"{result.mean(p):.2f} (median {summary['policies'][p]['median']:g})" for p in policies]
            diffs = [
                f"{p} {d['mean']:+.2f} [{d['ci95'][0]:+.2f}, {d['ci95'][1]:+.2f}]"
                for p in policies
                if p != args.reference
                for d in [summary["policies"][p][f"minus_{args.reference}"]]
            ]
            print(
                f"| {result.dataset} | {result.worlds.size} | {' | '.join(cells)} | "
                f"{summary['oracle_bound']:.2f} | {'; '.join(diffs)} |",
                flush=True,
            )
    except DrdError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(
        f"\n{args.folds} folds over the feasible worlds, seed {args.seed}; eta, kappa and the region rule validated "
        "per fold on its training worlds."
    )
    if args.json is not None:
        args.json.write_text(json.dumps(summaries, indent=2) + "\n", encoding="utf-8")
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
