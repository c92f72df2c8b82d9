#!/usr/bin/env python3
"""A prior built from a site file against BiSECt on the site's held-out worlds (a report, not a timed test).

Runs, in ``--out`` (each step skipped when its file is there, so an interrupted run resumes):

1. ``drd build-dataset --site-file SITE --worlds N --seed S --k 10`` -> ``ds.npz`` (the site's own query: the
   lattice's start and goal);
2. ``drd build-tree --dataset ds.npz`` -> ``prior.npz`` (eta and kappa validated on held-out training worlds);
3. ``drd bench --dataset ds.npz --prior prior.npz --policies direct_bisect,bisect,lazysp`` -> ``bench.json``:
   mean checks on the dataset's held-out test worlds with the prior's own tree and settings;
4. ``scripts/experiments/cross_validate_stages.py ds.npz --folds F`` -> ``cv.json``: every feasible world
   held out once (per fold the tree, eta and kappa come from the other folds), with the share of
   ``direct_bisect``'s checks the DiRECt tree stage chose.

Then it prints how many checks the prior saves against BiSECt (held-out and cross-validated, with the 95 %
interval of the difference) and how much the tree stage is used.

Usage:
  python scripts/experiments/bench_site.py sites/front_range/site.yaml --worlds 600 --seed 1 --out out/site_bench
      [--workers 2] [--folds 5]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent


def _run(argv: list[str], log: Path) -> float:
    """Run ``argv`` with its output appended to ``log``; its wall seconds. Exits on failure."""
    start = time.perf_counter()
    with open(log, "a") as out:
        out.write("$ " + " ".join(argv) + "\n")
        out.flush()
        done = subprocess.run(argv, stdout=out, stderr=subprocess.STDOUT, check=False)
    if done.returncode != 0:
        sys.exit(f"bench_site: {' '.join(argv[:4])} ... failed ({done.returncode}); see {log}")
    return time.perf_counter() - start


def _drd(*args: str) -> list[str]:
    return [sys.executable, "-m", "drd_planner.cli.main", *args]


def _steps(args: argparse.Namespace, out: Path) -> dict[str, float]:
    """Run the missing steps; their wall seconds."""
    log, seconds = out / "log.txt", {}
    ds, prior = out / "ds.npz", out / "prior.npz"
    if not ds.is_file():
        seconds["dataset"] = _run(
            _drd(
                "build-dataset", "--site-file", str(args.site), "--worlds", str(args.worlds), "--seed", str(args.seed),
                "--k", "10", "--max-paths", "500", "--test-fraction", "0.1", "--workers", str(args.workers),
                "--no-trajectories", "--out", str(ds),
            ),
            log,
        )  # fmt: skip
    if not prior.is_file():
        seconds["prior"] = _run(_drd("build-tree", "--dataset", str(ds), "--out", str(prior)), log)
    if not (out / "bench.json").is_file():
        seconds["bench"] = _run(
            _drd(
                "bench", "--dataset", str(ds), "--prior", str(prior), "--policies", "direct_bisect,bisect,lazysp",
                "--json", str(out / "bench.json"),
            ),
            log,
        )  # fmt: skip
    if not (out / "cv.json").is_file():
        cv = [sys.executable, str(HERE / "cross_validate_stages.py"), str(ds), "--folds", str(args.folds)]
        seconds["cross_validation"] = _run([*cv, "--seed", "0", "--json", str(out / "cv.json")], log)
    return seconds


def _held_out(bench: dict[str, Any]) -> dict[str, float]:
    """Mean checks per policy on the dataset's test worlds."""
    return {name: float(p["mean_checks"]) for name, p in bench["policies"].items() if "mean_checks" in p}


def _report(out: Path, seconds: dict[str, float]) -> str:
    from drd_planner.data.dataset_file import load_dataset

    ds = load_dataset(out / "ds.npz")
    bench = json.loads((out / "bench.json").read_text())
    cv = json.loads((out / "cv.json").read_text())
    feasible = int(ds.test_ids.size)
    lines = [
        f"dataset: {ds.num_worlds} worlds x {ds.graph.num_edges} edges, {ds.library.num_paths} library paths, "
        f"{ds.train_ids.size} train / {ds.test_ids.size} test worlds",
        f"prior: eta {bench['settings']['eta']:g}, kappa {bench['settings']['pseudo_count']}, tree of "
        f"{bench['tree']['nodes']} nodes (depth {bench['tree']['depth']}) over {bench['tree']['num_train_worlds']} "
        "training worlds",
    ]
    held = _held_out(bench)
    if {"direct_bisect", "bisect"} <= set(held):
        d, b = held["direct_bisect"], held["bisect"]
        lines.append(
            f"held-out test worlds ({feasible}): direct_bisect {d:.2f}, bisect {b:.2f}, "
            f"lazysp {held.get('lazysp', 0):.2f} mean checks: the prior needs {100 * (1 - d / b):.1f} % fewer "
            "checks than BiSECt"
        )
    pol = cv["policies"]
    diff = pol["direct_bisect"]["minus_bisect"]
    d, b = pol["direct_bisect"]["mean"], pol["bisect"]["mean"]
    lines.append(
        f"cross-validated ({cv['num_worlds']} feasible worlds, {cv['settings']['folds']} folds): "
        f"direct_bisect {d:.2f}, bisect {b:.2f}, lazysp {pol['lazysp']['mean']:.2f}; difference {diff['mean']:+.2f} "
        f"[{diff['ci95'][0]:+.2f}, {diff['ci95'][1]:+.2f}] ({100 * (1 - d / b):.1f} % fewer)"
    )
    etas = ", ".join(f"{e:g}" for e in cv["etas"])
    lines.append(f"tree stage: {100 * cv['tree_stage_share']:.1f} % of direct_bisect's checks (fold etas {etas})")
    if seconds:
        lines.append("wall seconds: " + ", ".join(f"{k} {v:.0f}" for k, v in seconds.items()))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("site", type=Path, help="site file (drd-site/1)")
    parser.add_argument("--worlds", type=int, default=600)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--folds", type=int, default=5)
    parser.add_argument("--out", type=Path, required=True, help="folder for ds.npz, prior.npz, bench.json, cv.json")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    seconds = _steps(args, args.out)
    report = _report(args.out, seconds)
    print(report)
    (args.out / "report.txt").write_text(report + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
