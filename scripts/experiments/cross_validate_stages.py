#!/usr/bin/env python3
"""Cross-validation per fold, with the share of checks the DiRECt tree stage makes (before BiSECt takes over).

``scripts/experiments/cross_validate.py`` gives the means over every feasible world; this script runs the same folds
(``drd_planner.bench.cross_validation.cross_validate``, same deal of worlds, same per-fold validation of eta
and kappa, same episodes) and adds, per fold, each policy's mean checks and, for ``direct_bisect``, the
validated eta / kappa, the tree's size and how many of its checks the tree stage chose. That share is
measured by replaying every ``direct_bisect`` episode (``drd_planner.bench.runner.run_world``, the same seed
as the benchmark used) with the fold's tree and settings and counting the check log's ``tree`` records; the
replayed check counts are compared with the benchmark's, so the share belongs to exactly those episodes.

Usage:
  python scripts/experiments/cross_validate_stages.py datasets/heli_lines.npz [--folds 10] [--seed 0]
      [--policies direct_bisect,bisect,lazysp] [--json FILE]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from drd_planner.bench.cross_validation import CrossValidationResult, cross_validate
from drd_planner.bench.runner import PolicySettings, check_policy_names, run_world, train_bias
from drd_planner.core.policies import DEFAULT_ALPHA
from drd_planner.core.problem import Problem
from drd_planner.core.tree import DEFAULT_EXPAND_THRESHOLD, build_tree
from drd_planner.data.dataset_file import load_dataset_problem
from drd_planner.exceptions import DrdError

TREE_POLICY = "direct_bisect"


def _fold_problem(problem: Problem, held: np.ndarray) -> Problem:
    """The problem whose training worlds are all but ``held`` and whose test worlds are ``held``."""
    worlds = problem.require_worlds()
    fit = np.setdiff1d(np.arange(worlds.num_worlds, dtype=np.int64), held)
    return dataclasses.replace(problem, worlds=worlds.subset(fit, np.sort(held)))


def _tree_stage(problem: Problem, result: CrossValidationResult, fold: int) -> dict[str, Any]:
    """Replay fold ``fold``'s ``direct_bisect`` episodes: tree size, eta, kappa and the tree stage's checks."""
    held = result.worlds[result.fold_of == fold]
    sub = _fold_problem(problem, held)
    eta = result.etas[fold]
    kappa = result.settings["chosen_pseudo_counts"][fold]
    rule = result.settings["chosen_region_rules"][fold]
    options = dict(result.settings.get("tree_options") or {})
    expand = float(options.pop("expand_threshold", DEFAULT_EXPAND_THRESHOLD))
    tree = build_tree(sub, expand_threshold=expand, progress=False, **{**options, "region_rule": rule})
    theta = train_bias(sub, alpha=DEFAULT_ALPHA)
    settings = PolicySettings(eta, DEFAULT_ALPHA, kappa)
    seed = int(result.settings["seed"])
    test_ids = sub.require_worlds().test_ids
    expected = dict(zip(result.worlds.tolist(), result.checks[TREE_POLICY].tolist(), strict=True))
    tree_checks = total = 0
    for k, world in enumerate(test_ids.tolist()):
        episode = run_world(sub, TREE_POLICY, world, theta=theta, tree=tree, seed=seed + k, settings=settings)
        if episode.num_checks != expected[world]:
            raise DrdError(
                f"fold {fold}: replay of world {world} made {episode.num_checks} checks, "
                f"the benchmark {expected[world]}"
            )
        tree_checks += sum(1 for record in episode.checks if record.stage == "tree")
        total += episode.num_checks
    return {
        "eta": eta,
        "kappa": kappa,
        "tree_nodes": tree.num_nodes,
        "tree_depth": tree.depth(),
        "tree_checks": tree_checks,
        "checks": total,
        "tree_share": tree_checks / total if total else 0.0,
    }


def _report(problem: Problem, result: CrossValidationResult, policies: tuple[str, ...]) -> dict[str, Any]:
    """Print the per-fold table and the means; return them as JSON."""
    folds = int(result.settings["folds"])
    rows: list[dict[str, Any]] = []
    print(f"| fold | worlds | {' | '.join(policies)} | eta | kappa | tree nodes | tree-stage share |")
    print(f"|---:|---:|{'---:|' * len(policies)}---:|---:|---:|---:|")
    for fold in range(folds):
        mask = result.fold_of == fold
        means = {p: float(result.checks[p][mask].mean()) for p in policies}
        stage = _tree_stage(problem, result, fold) if TREE_POLICY in policies else {}
        rows.append({"fold": fold, "worlds": int(mask.sum()), "mean_checks": means, **stage})
        cells = " | ".join(f"{means[p]:.2f}" for p in policies)
        extra = (
            f"{stage['eta']:g} | {stage['kappa']} | {stage['tree_nodes']} | {100 * stage['tree_share']:.1f} %"
            if stage
            else "- | - | - | -"
        )
        print(f"| {fold} | {int(mask.sum())} | {cells} | {extra} |", flush=True)
    means = {p: result.mean(p) for p in policies}
    tree_checks = sum(r.get("tree_checks", 0) for r in rows)
    all_checks = sum(r.get("checks", 0) for r in rows)
    share = tree_checks / all_checks if all_checks else 0.0
    print(
        f"| mean | {result.worlds.size} | {' | '.join(f'{means[p]:.2f}' for p in policies)} | | | | "
        f"{100 * share:.1f} % |"
    )
    summary = result.as_json("bisect" if "bisect" in policies else None)
    summary.update({"folds_detail": rows, "tree_stage_share": share, "means": means})
    for p in policies:
        if p != TREE_POLICY and TREE_POLICY in policies:
            print(
                f"{TREE_POLICY} vs {p}: {means[TREE_POLICY] / means[p]:.3f} of its checks "
                f"({100 * (1 - means[TREE_POLICY] / means[p]):+.1f} % fewer)"
            )
    return summary


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("dataset", type=Path, help="dataset file written by drd build-dataset")
    parser.add_argument("--folds", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--policies", default="direct_bisect,bisect,lazysp")
    parser.add_argument("--json", type=Path, default=None, help="write the summary here")
    args = parser.parse_args(argv)
    policies = tuple(p.strip() for p in args.policies.split(",") if p.strip())
    try:
        check_policy_names(policies)
        t0 = time.perf_counter()
        problem = load_dataset_problem(args.dataset)
        result = cross_validate(problem, policies=policies, folds=args.folds, seed=args.seed)
        summary = _report(problem, result, policies)
    except DrdError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    summary["seconds"] = time.perf_counter() - t0
    print(
        f"\n{args.folds} folds over {result.worlds.size} feasible worlds, seed {args.seed}; {summary['seconds']:.0f} s"
    )
    if args.json is not None:
        args.json.write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
