#!/usr/bin/env python3
"""Core speed benchmark (a script that measures and reports; not a unit test).

Reports, side by side in one run on the same machine:
  * DiRECt tree build time on dataset_2d_2 (900 worlds, 2524 edges, 500 paths), for the default
    tree (MaxProbReg candidates) and the full-candidate tree, and the full build's FLOP rate in
    its ECD-weight products as a fraction of a plain float32 numpy matmul of the root's size;
  * BiSECt (MaxProbReg) selection time per step at m = 500;
  * tree walking time per step (select + observe while in the tree stage).

Usage: python scripts/experiments/bench_core_speed.py [--gccd ../shared/data/gccd] [--repeats 3]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from drd_planner.core.bisect import Bisect, bias_from_worlds
from drd_planner.core.policies import DirectBisectPolicy
from drd_planner.core.problem import Problem
from drd_planner.core.tree import DecisionTree, build_tree
from drd_planner.data.gccd import load_gccd_folder


def matmul_rate(m: int, k: int, n: int, repeats: int) -> float:
    """GFLOP/s of a plain float32 (m x k) @ (k x n) numpy matmul, best of ``repeats``."""
    rng = np.random.default_rng(0)
    a = rng.random((m, k), dtype=np.float32)
    b = rng.random((k, n), dtype=np.float32)
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        a @ b
        best = min(best, time.perf_counter() - t0)
    return 2.0 * m * k * n / best / 1e9


def time_tree_builds(problem: Problem, repeats: int) -> dict[str, DecisionTree]:
    """The fastest of ``repeats`` builds of the default and the full-candidate tree, by label; prints each."""
    builds = {}
    for label, mpr in (("default (MaxProbReg candidates)", True), ("full (all edges as candidates)", False)):
        best = None
        for _ in range(repeats):
            tree = build_tree(problem, progress=False, max_prob_region=mpr)
            if best is None or tree.info["build_seconds"] < best.info["build_seconds"]:
                best = tree
        assert best is not None
        builds[label] = best
        info = best.info
        rate = info["matmul_flops"] / info["build_seconds"] / 1e9
        print(
            f"tree build, {label}: {info['build_seconds']:.3f} s, {best.num_nodes} nodes, depth {best.depth()}, "
            f"{info['matmul_flops'] / 1e9:.2f} GFLOP in ECD products -> {rate:.1f} GFLOP/s"
        )
    return builds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--gccd", default=str(Path(__file__).resolve().parents[3] / "shared" / "data" / "gccd"))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--json", help="also write the numbers here")
    args = parser.parse_args()

    problem = load_gccd_folder(Path(args.gccd) / "dataset_2d_2")
    worlds = problem.require_worlds()
    n_train = worlds.train_ids.size
    print(f"dataset_2d_2: {n_train} training worlds, {problem.num_edges} edges, {problem.num_paths} paths")

    builds = time_tree_builds(problem, args.repeats)
    full = builds["full (all edges as candidates)"]
    full_rate = full.info["matmul_flops"] / full.info["build_seconds"] / 1e9
    ref_rate = matmul_rate(problem.num_paths, n_train, 2 * problem.num_edges, args.repeats + 2)
    print(
        f"plain numpy float32 matmul ({problem.num_paths} x {n_train}) @ ({n_train} x {2 * problem.num_edges}): "
        f"{ref_rate:.1f} GFLOP/s; full tree build achieves {100 * full_rate / ref_rate:.0f}% of it "
        f"(whole build wall time, selection overheads included)"
    )

    # BiSECt selection time per step at m = 500.
    theta = bias_from_worlds(worlds.X[worlds.train_ids])
    times = []
    for world in worlds.test_ids:
        bis = Bisect(problem.library, theta, problem.edge_costs)
        x = worlds.X[world]
        while True:
            t0 = time.perf_counter()
            edge = bis.select()
            times.append(time.perf_counter() - t0)
            if edge is None:
                break
            bis.observe(edge, bool(x[edge]))
    bisect_ms = 1e3 * float(np.mean(times))
    print(
        f"BiSECt (MaxProbReg) selection at m = {problem.num_paths}: {bisect_ms:.3f} ms per step (mean of {len(times)})"
    )

    # Tree walking per step.
    tree = builds["default (MaxProbReg candidates)"]
    walk = []
    for world in worlds.test_ids:
        policy = DirectBisectPolicy(tree, problem.library, problem.edge_costs)
        x = worlds.X[world]
        while policy.stage == "tree":
            t0 = time.perf_counter()
            edge = policy.select()
            assert edge is not None
            if policy.stage != "tree":
                break
            policy.observe(edge, bool(x[edge]))
            walk.append(time.perf_counter() - t0)
    walk_us = 1e6 * float(np.mean(walk)) if walk else float("nan")
    print(
        f"tree walk: {walk_us:.1f} us per step (select + observe, mean of {len(walk)}; includes the BiSECt hand-over)"
    )

    if args.json:
        Path(args.json).write_text(
            json.dumps(
                {
                    "build_seconds_default": builds["default (MaxProbReg candidates)"].info["build_seconds"],
                    "build_seconds_full": full.info["build_seconds"],
                    "full_build_gflops": full_rate,
                    "matmul_gflops": ref_rate,
                    "bisect_select_ms": bisect_ms,
                    "tree_walk_us": walk_us,
                },
                indent=1,
            )
        )


if __name__ == "__main__":
    main()
