#!/usr/bin/env python3
"""The real-scale helicopter lattice (``trees/heli_lines_spec.json``): its size, build time and edge-check time.

Reports the lattice (vertices, edges, extent, levels, headings, trajectory samples), the time to build it
(the domain from its spec: grid, primitives, pruning, every edge's samples; best of ``--repeats``), and per
world of the ``corridors`` model: the time to draw the world, to build its checker (FCL scene and the
prefilter), and to check edges once batched (``check_many``: every edge, what the dataset builder does)
and one by one (``check``: ``--single`` edges spread over the graph, what the node does when the tree asks
for one edge). Times are CPU seconds of this one process (``time.process_time``), so they are one-core
figures on a shared machine; wall-clock totals are printed too.

Usage: python scripts/experiments/bench_heli_lines.py [--spec trees/heli_lines_spec.json] [--worlds 5] [--single 500]
    [--repeats 3] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from drd_planner.domains.helicopter import HelicopterDomain

REPO = Path(__file__).resolve().parents[2]


def _cpu(fn: Any) -> tuple[Any, float]:
    """``fn()`` and the CPU seconds it took."""
    t0 = time.process_time()
    out = fn()
    return out, time.process_time() - t0


def _lattice(spec: dict[str, Any], repeats: int) -> tuple[HelicopterDomain, dict[str, Any]]:
    """The domain (best of ``repeats`` builds) and the lattice's numbers."""
    times = []
    domain: HelicopterDomain | None = None
    for _ in range(repeats):
        domain, seconds = _cpu(lambda: HelicopterDomain.from_spec(spec))
        times.append(seconds)
    assert domain is not None
    lattice = domain.lattice
    states = domain.graph.vertex_states
    assert states is not None
    samples = np.diff(lattice.offsets)
    p = lattice.params
    return domain, {
        "vertices": int(domain.graph.num_vertices),
        "edges": int(domain.graph.num_edges),
        "extent_m": [float(np.ptp(p.x_range)), float(np.ptp(p.y_range))],
        "levels": len(p.z_levels),
        "headings": int(np.unique(np.round(states[:, 3], 6)).size),
        "samples_per_edge_mean": float(samples.mean()),
        "samples_total": int(samples.sum()),
        "build_s_best": float(min(times)),
        "build_s_all": times,
    }


def _world(domain: HelicopterDomain, seed: int, single: int) -> dict[str, Any]:
    """Draw, checker-build and check times of one world (CPU seconds, ms per edge)."""
    world, draw_s = _cpu(lambda: domain.make_world("corridors", seed))
    checker, build_s = _cpu(lambda: domain.checker(world))
    edges = np.arange(domain.graph.num_edges)
    free, many_s = _cpu(lambda: checker.check_many(edges))
    picked = np.linspace(0, edges.size - 1, min(single, edges.size)).astype(np.int64)
    answers, one_s = _cpu(lambda: [checker.check(int(e)) for e in picked])
    if not np.array_equal(np.asarray(answers), free[picked]):
        raise SystemExit(f"world {seed}: check() and check_many() disagree")
    return {
        "seed": seed,
        "free": float(free.mean()),
        "draw_s": draw_s,
        "checker_build_s": build_s,
        "check_many_ms_per_edge": 1e3 * many_s / edges.size,
        "check_ms_per_edge": 1e3 * one_s / picked.size,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--spec", type=Path, default=REPO / "trees" / "heli_lines_spec.json")
    parser.add_argument("--worlds", type=int, default=5)
    parser.add_argument("--single", type=int, default=500, help="edges checked one by one per world")
    parser.add_argument("--repeats", type=int, default=3, help="lattice builds (the best is reported)")
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args(argv)
    wall = time.perf_counter()
    spec = json.loads(args.spec.read_text(encoding="utf-8"))
    domain, lattice = _lattice(spec, args.repeats)
    print(
        f"lattice: {lattice['vertices']} vertices, {lattice['edges']} edges over "
        f"{lattice['extent_m'][0]:.0f} x {lattice['extent_m'][1]:.0f} m, {lattice['levels']} levels, "
        f"{lattice['headings']} headings, {lattice['samples_per_edge_mean']:.1f} samples per edge; "
        f"built in {lattice['build_s_best']:.3f} s (best of {args.repeats})"
    )
    worlds = [_world(domain, seed, args.single) for seed in range(args.worlds)]
    print("| world | free | draw s | checker build s | check_many ms/edge | check() ms/edge |")
    print("|---:|---:|---:|---:|---:|---:|")
    for w in worlds:
        print(
            f"| {w['seed']} | {w['free']:.2f} | {w['draw_s']:.3f} | {w['checker_build_s']:.3f} | "
            f"{w['check_many_ms_per_edge']:.4f} | {w['check_ms_per_edge']:.4f} |"
        )
    means = {k: float(np.mean([w[k] for w in worlds])) for k in worlds[0] if k != "seed"}
    print(
        f"| mean | {means['free']:.2f} | {means['draw_s']:.3f} | {means['checker_build_s']:.3f} | "
        f"{means['check_many_ms_per_edge']:.4f} | {means['check_ms_per_edge']:.4f} |"
    )
    print(f"wall time {time.perf_counter() - wall:.1f} s")
    if args.json is not None:
        payload = {"lattice": lattice, "worlds": worlds, "means": means}
        args.json.write_text(json.dumps(payload, indent=2) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
