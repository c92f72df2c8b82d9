"""The ``drd`` command line: build trees, benchmark policies, plan once, and a self-contained demo."""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from drd_planner import __version__
from drd_planner.core.episode import EpisodeResult
from drd_planner.core.problem import Problem
from drd_planner.core.tree import DecisionTree
from drd_planner.exceptions import DrdError


def _policies(text: str) -> list[str]:
    return [p.strip() for p in text.split(",") if p.strip()]


def _tree_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--threshold", type=float, default=0.05, help="expand nodes with at least this fraction"
    )
    parser.add_argument(
        "--candidates",
        choices=("max-prob-region", "all"),
        default="max-prob-region",
        help="tests DiRECt considers at a node (default: edges of the best-supported path)",
    )
    parser.add_argument("--top-regions", type=int, default=None, help="IncDRD: DiRECt on k regions only")
    parser.add_argument(
        "--colouring", action="store_true", help="group never-overlapping regions into one ECD"
    )


def _build_tree_from_args(problem: Problem, args: argparse.Namespace) -> DecisionTree:
    from drd_planner.core.tree import build_tree

    return build_tree(
        problem,
        expand_threshold=args.threshold,
        colouring=args.colouring,
        top_regions=args.top_regions,
        max_prob_region=args.candidates == "max-prob-region",
    )


def cmd_build_tree(args: argparse.Namespace) -> int:
    """``drd build-tree``: build a DiRECt tree from a dataset's training worlds and save it."""
    from drd_planner.data.gccd import load_gccd_folder
    from drd_planner.data.tree_file import TreeBundle, save_tree

    problem = load_gccd_folder(args.gccd)
    tree = _build_tree_from_args(problem, args)
    bundle = TreeBundle(
        problem=dataclasses.replace(problem, worlds=None),
        tree=tree,
        domain="gccd",
        provenance={"command": " ".join(sys.argv), "dataset": problem.name, "software": __version__},
    )
    out = save_tree(args.out, bundle)
    print(
        f"wrote {out}: {tree.num_nodes} nodes, depth {tree.depth()}, built in {tree.info['build_seconds']:.2f} s"
    )
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    """``drd bench``: every policy on every test world of an authors'-format dataset."""
    from drd_planner.bench.runner import benchmark_json, markdown_table, run_benchmark
    from drd_planner.data.gccd import load_gccd_folder
    from drd_planner.data.tree_file import check_bundle_fits, load_tree

    problem = load_gccd_folder(args.gccd)
    tree = None
    if args.tree:
        bundle = load_tree(args.tree, expected_domain="gccd")
        check_bundle_fits(bundle, problem)
        tree = bundle.tree
    elif any(p in ("direct_bisect", "direct_only") for p in args.policies):
        tree = _build_tree_from_args(problem, args)
    result = run_benchmark(
        problem, policies=args.policies, tree=tree, seed=args.seed, eta=args.eta, max_worlds=args.max_worlds
    )
    doc = benchmark_json(result)
    table = markdown_table([result], args.policies)
    print(table, end="")
    if args.json:
        Path(args.json).write_text(json.dumps(doc, indent=1))
        print(f"wrote {args.json}")
    if args.markdown:
        Path(args.markdown).write_text(table)
    return 0


def cmd_plan(args: argparse.Namespace) -> int:
    """``drd plan``: one offline plan with a saved tree on one world of a dataset (no ROS)."""
    from drd_planner.core.bisect import bias_from_worlds
    from drd_planner.core.episode import TableOracle, run_episode
    from drd_planner.core.policies import POLICIES, PolicyContext
    from drd_planner.data.gccd import load_gccd_folder
    from drd_planner.data.tree_file import check_bundle_fits, load_tree

    bundle = load_tree(args.tree, expected_domain="gccd")
    problem = load_gccd_folder(args.gccd)
    check_bundle_fits(bundle, problem)
    worlds = problem.require_worlds()
    if not 0 <= args.world < worlds.num_worlds:
        raise DrdError(f"--world must lie in [0, {worlds.num_worlds})")
    theta = bias_from_worlds(worlds.X[worlds.train_ids], alpha=bundle.alpha)
    ctx = PolicyContext(
        problem.library, problem.edge_costs, theta, bundle.tree, args.seed, bundle.eta, bundle.alpha
    )
    policy = POLICIES[args.policy](ctx)
    result = run_episode(problem.library, problem.edge_costs, policy, TableOracle(worlds.X[args.world]))
    _print_episode(problem, result)
    return 0 if result.success else 1


def _print_episode(problem: Problem, result: EpisodeResult) -> None:
    graph = problem.graph
    for rec in result.checks:
        ends = ""
        if graph is not None:
            u, v = graph.edges[rec.edge]
            ends = f" ({u}->{v})"
        state = "free   " if rec.free else "BLOCKED"
        print(f"  check {rec.step + 1:3d}: edge {rec.edge:5d}{ends:14s} {state} [{rec.stage}]")
    if result.success and result.path_index is not None:
        path = problem.library.path_edges[result.path_index]
        print(
            f"  -> path {result.path_index} ({path.size} edges) verified free after {result.num_checks} checks"
        )
    else:
        print(f"  -> {result.status.value} after {result.num_checks} checks")


def cmd_demo(args: argparse.Namespace) -> int:
    """``drd demo``: generate a planar problem, build a tree, plan on a few held-out worlds."""
    from drd_planner.bench.runner import run_benchmark
    from drd_planner.core.bisect import bias_from_worlds
    from drd_planner.core.episode import TableOracle, run_episode
    from drd_planner.core.policies import POLICIES, PolicyContext
    from drd_planner.core.tree import build_tree
    from drd_planner.domains.planar import make_planar_problem

    print(f"drd demo: planar '{args.model}' world model, {args.worlds} worlds, seed {args.seed}")
    problem = make_planar_problem(model=args.model, num_worlds=args.worlds, seed=args.seed)
    worlds = problem.require_worlds()
    assert problem.graph is not None
    print(
        f"graph: {problem.graph.num_vertices} vertices, {problem.num_edges} edges; library: {problem.num_paths} "
        f"paths; {worlds.train_ids.size} training / {worlds.test_ids.size} test worlds"
    )
    tree = build_tree(problem, progress=False)
    print(
        f"DiRECt tree: {tree.num_nodes} nodes, depth {tree.depth()}, built in {tree.info['build_seconds']:.2f} s"
    )
    theta = bias_from_worlds(worlds.X[worlds.train_ids])
    for k, world in enumerate(worlds.test_ids[: args.episodes]):
        ctx = PolicyContext(problem.library, problem.edge_costs, theta, tree, args.seed + k)
        result = run_episode(
            problem.library, problem.edge_costs, POLICIES["direct_bisect"](ctx), TableOracle(worlds.X[world])
        )
        print(f"test world {int(world)} (direct_bisect):")
        _print_episode(problem, result)
    policies = ["direct_bisect", "bisect", "bisect_all"]
    bench = run_benchmark(problem, policies=policies, tree=tree, seed=args.seed, progress=False)
    means = {p: float(np.mean(bench.policies[p].checks)) for p in policies}
    summary = ", ".join(f"{p} {v:.2f}" for p, v in means.items())
    print(
        f"mean checks over {len(bench.test_ids)} test worlds: {summary}; oracle bound {np.nanmean(bench.lower_bound):.2f}"
    )
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``drd``."""
    parser = argparse.ArgumentParser(prog="drd", description="DiRECt + BiSECt active edge evaluation.")
    parser.add_argument("--version", action="version", version=f"drd_planner {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("build-tree", help="build a DiRECt decision tree file from a dataset")
    p.add_argument("--gccd", required=True, help="authors'-format dataset folder")
    p.add_argument("--out", required=True, help="tree file to write (.npz)")
    _tree_options(p)
    p.set_defaults(func=cmd_build_tree)

    p = sub.add_parser("bench", help="benchmark policies on a dataset's test worlds")
    p.add_argument("--gccd", required=True, help="authors'-format dataset folder")
    p.add_argument(
        "--policies", type=_policies, default=["direct_bisect", "direct_only", "bisect", "bisect_all"]
    )
    p.add_argument("--json", help="write the results JSON here")
    p.add_argument("--markdown", help="write the results table here")
    p.add_argument("--tree", help="use this tree file instead of building one")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--eta", type=float, default=0.2, help="switch to BiSECt at or below this fraction")
    p.add_argument("--max-worlds", type=int, default=None, help="only the first K test worlds")
    _tree_options(p)
    p.set_defaults(func=cmd_bench)

    p = sub.add_parser("plan", help="plan once offline with a tree file on one dataset world")
    p.add_argument("--tree", required=True)
    p.add_argument("--gccd", required=True)
    p.add_argument("--world", type=int, required=True, help="0-based world row")
    p.add_argument(
        "--policy", default="direct_bisect", choices=("direct_bisect", "direct_only", "bisect", "bisect_all")
    )
    p.add_argument("--seed", type=int, default=0)
    p.set_defaults(func=cmd_plan)

    p = sub.add_parser("demo", help="self-contained demo on a generated planar problem")
    p.add_argument("--model", default="one_wall", choices=("one_wall", "forest", "moving_wall"))
    p.add_argument("--worlds", type=int, default=300)
    p.add_argument("--episodes", type=int, default=3)
    p.add_argument("--seed", type=int, default=0)
    p.set_defaults(func=cmd_demo)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; errors print one line and exit 2."""
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args))
    except DrdError as exc:
        print(f"drd: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("drd: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
