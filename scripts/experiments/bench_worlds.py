#!/usr/bin/env python3
"""Real-world checking speed, side by side in one run: helicopter and arm edges per second per core,
and the dataset-generation speed-up of 2 workers over 1.

Edge throughput is measured in one process on one thread and reported per CPU-second (process time), so
it is the one-core figure even when the machine is shared; wall-clock figures are printed next to it.
For every world the checker is built first (scene construction is timed separately) and then asked for
every edge of the graph, once batched (`check_many`, what the dataset builder uses) and once edge by
edge (`check`, what the node does when the tree asks for one edge).

The speed-up part runs `scripts/experiments/bench_dataset_speedup.py` (the real `drd build-dataset` command in fresh
processes, byte-identical outputs checked) on the helicopter Wires model and reports its result.

Usage: python scripts/experiments/bench_worlds.py [--worlds 5] [--speedup-worlds 96] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from drd_planner.domains.base import domain_from_spec

CASES = (("helicopter", "wires"), ("helicopter", "terrain"), ("arm", "table_clutter"), ("arm", "clutter"))
GOAL = 2000.0


def _timed(fn: Any) -> tuple[Any, float, float]:
    c0, w0 = time.process_time(), time.perf_counter()
    out = fn()
    return out, time.process_time() - c0, time.perf_counter() - w0


def measure(domain_name: str, model: str, worlds: int) -> dict[str, Any]:
    """Edges per CPU-second for ``check_many`` and ``check`` over ``worlds`` seeded worlds."""
    domain = domain_from_spec(domain_name)
    edges = np.arange(domain.graph.num_edges)
    build_cpu = many_cpu = many_wall = one_cpu = one_wall = 0.0
    free = 0
    for seed in range(worlds):
        world = domain.make_world(model, seed)
        checker, c, _ = _timed(lambda w=world: domain.checker(w))
        build_cpu += c
        result, c, w = _timed(lambda ch=checker: ch.check_many(edges))
        many_cpu, many_wall = many_cpu + c, many_wall + w
        free += int(np.count_nonzero(result))
        checker = domain.checker(world)  # fresh: no cached answers
        single, c, w = _timed(lambda ch=checker: [ch.check(int(e)) for e in edges])
        one_cpu, one_wall = one_cpu + c, one_wall + w
        if list(np.asarray(result, dtype=bool)) != single:
            raise SystemExit(f"{domain_name}/{model} world {seed}: check_many and check disagree")
    total = worlds * edges.size
    return {
        "domain": domain_name,
        "model": model,
        "edges": int(edges.size),
        "worlds": worlds,
        "free_fraction": free / total,
        "check_many_edges_per_cpu_s": total / many_cpu,
        "check_many_edges_per_wall_s": total / many_wall,
        "check_edges_per_cpu_s": total / one_cpu,
        "check_edges_per_wall_s": total / one_wall,
        "scene_build_cpu_ms": 1e3 * build_cpu / worlds,
    }


def speedup(worlds: int) -> dict[str, Any]:
    """Run the dataset speed-up benchmark on helicopter Wires and return its JSON."""
    script = Path(__file__).with_name("bench_dataset_speedup.py")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "speedup.json"
        cmd = [sys.executable, str(script), "--domain", "helicopter", "--world-model", "wires"]
        cmd += ["--worlds", str(worlds), "--workers", "1,2", "--repeats", "1", "--json", str(out)]
        subprocess.run(cmd, check=True)
        data: dict[str, Any] = json.loads(out.read_text())
    return data


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--worlds", type=int, default=5, help="worlds per throughput case")
    parser.add_argument("--speedup-worlds", type=int, default=96, help="worlds of the 1-vs-2-worker build")
    parser.add_argument("--no-speedup", action="store_true")
    parser.add_argument("--json", help="write all numbers here")
    args = parser.parse_args()
    rows = [measure(d, m, args.worlds) for d, m in CASES]
    print("| domain / model | edges | free | check_many edges/CPU-s | check() edges/CPU-s | scene build ms |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        ok = "ok" if min(r["check_many_edges_per_cpu_s"], r["check_edges_per_cpu_s"]) >= GOAL else "BELOW GOAL"
        print(
            f"| {r['domain']} {r['model']} | {r['edges']} | {r['free_fraction']:.2f} | "
            f"{r['check_many_edges_per_cpu_s']:,.0f} | {r['check_edges_per_cpu_s']:,.0f} ({ok}) | "
            f"{r['scene_build_cpu_ms']:.0f} |"
        )
    doc: dict[str, Any] = {"throughput": rows}
    if not args.no_speedup:
        doc["speedup"] = speedup(args.speedup_worlds)
    if args.json:
        Path(args.json).write_text(json.dumps(doc, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
