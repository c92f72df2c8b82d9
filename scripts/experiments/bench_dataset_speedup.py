#!/usr/bin/env python3
"""Dataset-generation speed-up: ``drd build-dataset`` with 1 worker vs N local worker processes.

Runs the real command (``python -m drd_planner.cli.build_dataset build-dataset``, the code behind
``drd build-dataset``) in a fresh process per worker count and repeat, each from scratch into a
temporary folder; checks that every run wrote a byte-identical file; prints the best wall time per worker
count and the speed-up over the first count. The goal for 2 workers is >= 1.7x on an otherwise idle
machine with at least 2 cores. Worker counts are interleaved within each repeat, so a change of machine
load hits all of them alike, and the script also measures the ceiling the machine offers right now
(N processes vs 1 on a pure-CPU loop): on a busy machine that ceiling, not the builder, limits the result.

"wall" is the whole command (interpreter start, imports, edge checks, per-world k shortest paths,
joining, library, R, split, writing); "checks" is the parallel part alone, as the command reports it.

Usage:
  python scripts/experiments/bench_dataset_speedup.py [--domain planar] [--world-model one_wall] [--worlds 300]
      [--seed 0] [--chunk-size 8] [--workers 1,2] [--repeats 3] [--max-paths 500]
      [--domain-spec JSON|FILE] [--domain-factory MODULE:ATTR] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from drd_planner.cli.build_dataset import parse_domain_spec
from drd_planner.data.domain_factory import make_domain


def _counts(text: str) -> list[int]:
    counts = sorted({int(t) for t in text.split(",") if t.strip()})
    if not counts or counts[0] < 1:
        raise argparse.ArgumentTypeError("worker counts must be positive integers, e.g. 1,2")
    return counts


def _burn(n: int) -> float:
    t0 = time.perf_counter()
    total = 0
    for i in range(n):
        total += i * i
    return time.perf_counter() - t0


def machine_ceiling(workers: int, n: int = 3_000_000) -> float:
    """What ``workers`` processes gain over one on a pure-CPU loop right now (the builder's ceiling)."""
    t0 = time.perf_counter()
    for _ in range(workers):
        _burn(n)
    serial = time.perf_counter() - t0
    with multiprocessing.get_context("spawn").Pool(workers) as pool:
        pool.map(_burn, [1] * workers)  # start-up, not timed
        t0 = time.perf_counter()
        pool.map(_burn, [n] * workers)
        parallel = time.perf_counter() - t0
    return serial / parallel


def run_build(args: argparse.Namespace, model: str, workers: int, out: Path) -> tuple[float, float]:
    """(wall seconds, checks seconds) of one ``build-dataset`` run in a fresh process."""
    argv = [sys.executable, "-m", "drd_planner.cli.build_dataset", "build-dataset"]
    argv += ["--domain", args.domain, "--world-model", model, "--worlds", str(args.worlds)]
    argv += [
        "--seed",
        str(args.seed),
        "--chunk-size",
        str(args.chunk_size),
        "--max-paths",
        str(args.max_paths),
    ]
    argv += ["--workers", str(workers), "--out", str(out)]
    if args.domain_spec:
        argv += ["--domain-spec", args.domain_spec]
    if args.domain_factory:
        argv += ["--domain-factory", args.domain_factory]
    t0 = time.perf_counter()
    proc = subprocess.run(argv, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"build-dataset failed ({proc.returncode}): {proc.stderr.strip()}")
    found = re.search(r"checked in ([0-9.]+) s", proc.stdout)
    return wall, float(found.group(1)) if found else float("nan")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--domain", default="planar")
    parser.add_argument("--world-model", default=None, help="default: the domain's first world model")
    parser.add_argument("--worlds", type=int, default=300)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--chunk-size", type=int, default=8)
    parser.add_argument("--workers", type=_counts, default=[1, 2], help="comma-separated worker counts")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--max-paths", type=int, default=500)
    parser.add_argument("--domain-spec", default=None, help="inline JSON or a JSON file")
    parser.add_argument("--domain-factory", default=None, help="MODULE:ATTR for a domain outside the registry")
    parser.add_argument("--json", help="also write the numbers here")
    args = parser.parse_args()

    domain = make_domain(args.domain, parse_domain_spec(args.domain_spec), factory=args.domain_factory)
    model = args.world_model or domain.world_models[0]
    counts: list[int] = args.workers
    print(
        f"domain {domain.name} ({domain.graph.num_vertices} vertices, {domain.graph.num_edges} edges), "
        f"world model {model}, {args.worlds} worlds, chunk size {args.chunk_size}, seed {args.seed}; "
        f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f} before the runs"
    )
    runs: dict[int, list[dict[str, float]]] = {w: [] for w in counts}
    reference: bytes | None = None
    with tempfile.TemporaryDirectory(prefix="drd-speedup-") as tmp:
        for rep in range(args.repeats):
            for workers in counts:
                out = Path(tmp) / f"w{workers}_r{rep}.npz"
                wall, checks = run_build(args, model, workers, out)
                data = out.read_bytes()
                if reference is None:
                    reference = data
                elif data != reference:
                    raise SystemExit(f"error: the {workers}-worker build wrote a different file")
                out.unlink()
                runs[workers].append({"wall_s": wall, "checks_s": checks})
                print(
                    f"  repeat {rep + 1}/{args.repeats}, {workers} worker(s): {wall:7.2f} s wall, {checks:7.2f} s "
                    "checks"
                )
    best = {w: min(r["wall_s"] for r in runs[w]) for w in counts}
    best_checks = {w: min(r["checks_s"] for r in runs[w]) for w in counts}
    base = counts[0]
    print(f"\n| workers | best wall (s) | best checks (s) | speed-up vs {base} (wall) | (checks) |")
    print("|---:|---:|---:|---:|---:|")
    for w in counts:
        print(
            f"| {w} | {best[w]:.2f} | {best_checks[w]:.2f} | {best[base] / best[w]:.2f}x | "
            f"{best_checks[base] / best_checks[w]:.2f}x |"
        )
    ceiling = {w: machine_ceiling(w) for w in counts if w > 1}
    for w, c in ceiling.items():
        print(f"machine ceiling now: {w} processes run a pure-CPU loop {c:.2f}x faster than 1")
    if 1 in best and 2 in best:
        print(f"speed-up 1 -> 2 workers: {best[1] / best[2]:.2f}x wall (goal >= 1.7x); all files identical")
    if args.json:
        doc: dict[str, Any] = {
            "domain": domain.name,
            "world_model": model,
            "worlds": args.worlds,
            "chunk_size": args.chunk_size,
            "seed": args.seed,
            "cpus": os.cpu_count(),
            "runs": {str(w): runs[w] for w in counts},
            "best_wall_s": {str(w): best[w] for w in counts},
            "speedup_wall": {str(w): best[base] / best[w] for w in counts},
            "machine_ceiling": {str(w): c for w, c in ceiling.items()},
        }
        Path(args.json).write_text(json.dumps(doc, indent=1))
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
