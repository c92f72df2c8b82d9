#!/usr/bin/env python3
"""Where direct_bisect's savings come from, and where the method does not pay.

For every authors' graph dataset (``../shared/data/gccd``, 100 test worlds each) this runs, on the same
test worlds and seeds as ``drd bench``:

* ``bisect``: BiSECt on the training marginals (the paper's baseline);
* ``bisect_posterior``: BiSECt whose bias is re-conditioned on the training worlds from the first check
  (the posterior leaf alone, no tree; kappa as the default run validated it, 20 when it chose the fixed leaf);
* ``direct_bisect_fixed``: the paper's method exactly (tree with the paper's region rule, eta 0.2, fixed leaf);
* ``direct_bisect`` with the paper's rule and eta, kappa validated (what the tree and the posterior leaf give);
* ``direct_bisect`` as ``drd bench`` runs it by default (eta, kappa and the region rule validated).

Steps between them attribute the savings to the posterior leaf, the tree, validated settings and the
region rule. For the default ``direct_bisect`` it splits the checks into the path it proved, blocked edges
and free edges off that path, and it splits the test worlds by whether BiSECt's first path (the most
probable library path under the training marginals) is free: there BiSECt is already optimal up to the
path's length and the tree has nothing to gain.

Usage:
  python scripts/experiments/gain_sources.py [--root ../shared/data/gccd] [--sets dataset_2d_6,...] [--max-worlds K]
      [--json out/gain_sources.json]
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

from drd_planner.bench.runner import PolicySettings, run_world, train_bias
from drd_planner.bench.suite import SuiteOptions, discover_datasets, resolve_settings
from drd_planner.core.episode import EpisodeResult
from drd_planner.core.policies import DEFAULT_ALPHA, DEFAULT_ETA, DEFAULT_PSEUDO_COUNT
from drd_planner.core.problem import Problem
from drd_planner.core.region_rule import DEFAULT_REGION_RULE
from drd_planner.core.tree import build_tree
from drd_planner.data.gccd import load_gccd_folder

STEPS = ("bisect", "bisect_posterior", "direct_bisect_fixed", "direct_bisect_paper_rule", "direct_bisect")


def _first_path(problem: Problem, theta: np.ndarray) -> int:
    """The library path BiSECt proves first: the most probable under the training marginals."""
    logp = np.log(np.clip(theta, 1e-300, 1.0))
    scores = [float(logp[p].sum()) for p in problem.library.path_edges]
    return int(np.argmax(scores))


def run_set(folder: Path, max_worlds: int | None, seed: int) -> dict[str, Any]:
    """Every step on one dataset: per-world checks, the default's check split, settings and seconds."""
    t0 = time.perf_counter()
    problem = load_gccd_folder(folder)
    worlds = problem.require_worlds()
    test = worlds.test_ids[:max_worlds]
    theta = train_bias(problem)
    paper_opts = SuiteOptions(policies=("direct_bisect",), seed=seed, region_rules=(DEFAULT_REGION_RULE,))
    paper, paper_choice, _ = resolve_settings(problem, paper_opts)
    default, default_choice, rule_means = resolve_settings(
        problem, SuiteOptions(policies=("direct_bisect",), seed=seed)
    )
    paper_tree = build_tree(problem, progress=False, **dict(paper.tree_options))
    default_tree = build_tree(problem, progress=False, **dict(default.tree_options))
    kappa = default.pseudo_counts[0]
    runs: dict[str, tuple[Any, PolicySettings, str]] = {
        "bisect": (None, PolicySettings(DEFAULT_ETA, DEFAULT_ALPHA, None), "bisect"),
        "bisect_posterior": (
            paper_tree,
            PolicySettings(1.0, DEFAULT_ALPHA, DEFAULT_PSEUDO_COUNT if kappa is None else kappa),
            "bisect_posterior",
        ),
        "direct_bisect_fixed": (
            paper_tree,
            PolicySettings(DEFAULT_ETA, DEFAULT_ALPHA, None),
            "direct_bisect",
        ),
        "direct_bisect_paper_rule": (
            paper_tree,
            PolicySettings(float(paper.eta or DEFAULT_ETA), DEFAULT_ALPHA, paper.pseudo_counts[0]),
            "direct_bisect",
        ),
        "direct_bisect": (
            default_tree,
            PolicySettings(float(default.eta or DEFAULT_ETA), DEFAULT_ALPHA, kappa),
            "direct_bisect",
        ),
    }
    episodes: dict[str, list[EpisodeResult]] = {}
    for step, (tree, settings, policy) in runs.items():
        episodes[step] = [
            run_world(problem, policy, int(w), theta=theta, tree=tree, seed=seed + k, settings=settings)
            for k, w in enumerate(test)
        ]
    costs = problem.edge_costs
    path_costs = problem.library.path_costs(costs)
    oracle = [float(path_costs[worlds.R[w]].min()) for w in test]
    first = _first_path(problem, theta)
    first_free = [bool(worlds.R[w, first]) for w in test]
    split: dict[str, list[float]] = {"proved": [], "blocked": [], "free_off_path": []}
    for result in episodes["direct_bisect"]:
        on_path = set() if result.path_edges is None else set(result.path_edges.tolist())
        split["proved"].append(float(costs[list(on_path)].sum()) if on_path else 0.0)
        split["blocked"].append(float(sum(costs[c.edge] for c in result.checks if not c.free)))
        split["free_off_path"].append(
            float(sum(costs[c.edge] for c in result.checks if c.free and c.edge not in on_path))
        )
    return {
        "dataset": folder.name,
        "checks": {step: [r.total_cost(costs) for r in eps] for step, eps in episodes.items()},
        "failures": {step: sum(not r.success for r in eps) for step, eps in episodes.items()},
        "oracle": oracle,
        "first_path_free": first_free,
        "split": split,
        "settings": {
            "paper_rule": {"eta": paper.eta, "kappa": paper.pseudo_counts[0]},
            "default": {
                "eta": default.eta,
                "kappa": kappa,
                "region_rule": default.tree_options.get("region_rule", DEFAULT_REGION_RULE),
                "rule_means": rule_means,
            },
            "validations": [c.as_json() for c in (paper_choice, default_choice) if c is not None],
        },
        "seconds": time.perf_counter() - t0,
    }


def _mean(values: list[float], mask: list[bool] | None = None) -> float:
    picked = [v for i, v in enumerate(values) if mask is None or mask[i]]
    return float(np.mean(picked)) if picked else math.nan


def _geomean(values: list[float]) -> float:
    return math.exp(sum(math.log(v) for v in values) / len(values))


def report(rows: list[dict[str, Any]]) -> str:
    """Three markdown tables: the steps, the default's check split, and the first-path-free split."""
    out = [
        "| dataset | oracle | " + " | ".join(STEPS) + " | rule |",
        "|---|" + "---:|" * (len(STEPS) + 1) + "---|",
    ]
    for r in rows:
        cells = " | ".join(f"{_mean(r['checks'][s]):.2f}" for s in STEPS)
        out.append(
            f"| {r['dataset']} | {_mean(r['oracle']):.2f} | {cells} | {r['settings']['default']['region_rule']} |"
        )
    means = {s: [_mean(r["checks"][s]) for r in rows] for s in STEPS}
    oracle = [_mean(r["oracle"]) for r in rows]

    def ratio(a: str, b: str) -> float:
        return _geomean([x / y for x, y in zip(means[a], means[b], strict=True)])

    out += [
        "",
        "Geometric means over the sets (each step over the one before):",
        f"- posterior leaf alone: bisect_posterior / bisect {ratio('bisect_posterior', 'bisect'):.3f}",
        f"- the paper's tree: direct_bisect_fixed / bisect {ratio('direct_bisect_fixed', 'bisect'):.3f}",
        "- validated eta and kappa (paper's rule): direct_bisect_paper_rule / direct_bisect_fixed "
        f"{ratio('direct_bisect_paper_rule', 'direct_bisect_fixed'):.3f}",
        "- region rule validated: direct_bisect / direct_bisect_paper_rule "
        f"{ratio('direct_bisect', 'direct_bisect_paper_rule'):.3f}",
        f"- all together: direct_bisect / direct_bisect_fixed {ratio('direct_bisect', 'direct_bisect_fixed'):.3f}, "
        f"direct_bisect / bisect {ratio('direct_bisect', 'bisect'):.3f}",
        "- direct_bisect / oracle bound "
        f"{_geomean([m / o for m, o in zip(means['direct_bisect'], oracle, strict=True)]):.3f}",
        "",
        "| dataset | direct_bisect | oracle | proved path | blocked | free off the path | proved - oracle |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        sp = r["split"]
        out.append(
            f"| {r['dataset']} | {_mean(r['checks']['direct_bisect']):.2f} | {_mean(r['oracle']):.2f} | "
            f"{_mean(sp['proved']):.2f} | {_mean(sp['blocked']):.2f} | {_mean(sp['free_off_path']):.2f} | "
            f"{_mean(sp['proved']) - _mean(r['oracle']):.2f} |"
        )
    out += [
        "",
        "| dataset | worlds where BiSECt's first path is free | bisect there | direct_bisect there | "
        "bisect elsewhere | direct_bisect elsewhere |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        free = r["first_path_free"]
        other = [not f for f in free]
        c = r["checks"]
        out.append(
            f"| {r['dataset']} | {sum(free)} of {len(free)} | {_mean(c['bisect'], free):.2f} | "
            f"{_mean(c['direct_bisect'], free):.2f} | {_mean(c['bisect'], other):.2f} | "
            f"{_mean(c['direct_bisect'], other):.2f} |"
        )
    return "\n".join(out) + "\n"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--root", default=str(Path(__file__).resolve().parents[3] / "shared" / "data" / "gccd"))
    parser.add_argument("--sets", default="", help="comma-separated folder names (default: every graph set)")
    parser.add_argument("--max-worlds", type=int, default=None)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", default=None, help="write the per-world results here")
    args = parser.parse_args()
    root = Path(args.root)
    names = [s for s in args.sets.split(",") if s] or [f.name for f in discover_datasets(root)[0]]
    rows = []
    for name in names:
        try:
            rows.append(run_set(root / name, args.max_worlds, args.seed))
        except Exception as exc:  # a dataset the benchmark cannot run (no X, no test worlds): say so, go on
            print(f"skipped {name}: {exc}", file=sys.stderr)
            continue
        print(f"{name}: {rows[-1]['seconds']:.0f} s", file=sys.stderr, flush=True)
    text = report(rows)
    print(text, end="")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
