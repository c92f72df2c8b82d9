"""The ``drd`` command line: build datasets and trees, benchmark policies, plan once, and a demo."""

from __future__ import annotations

import argparse
import dataclasses
import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from drd_planner import __version__
from drd_planner.command_errors import run_command
from drd_planner.core.episode import EpisodeResult
from drd_planner.core.problem import Problem
from drd_planner.core.region_rule import DEFAULT_REGION_RULE, REGION_RULES
from drd_planner.core.tree import DEFAULT_EXPAND_THRESHOLD
from drd_planner.domains.planar import WORLD_MODELS as PLANAR_WORLD_MODELS
from drd_planner.exceptions import DrdError
from drd_planner.planner.commands import add_plan_parser
from drd_planner.planning.bag_cli import print_check

if TYPE_CHECKING:
    from drd_planner.bench.suite import SuiteOptions
    from drd_planner.planner.leaf_validation import PriorLeaf, TreeLeaf

#: ``--region-rule auto``: validate every region rule, each with its own eta and kappa.
AUTO = "auto"


def _policies(text: str) -> list[str]:
    return [p.strip() for p in text.split(",") if p.strip()]


def _tree_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--threshold",
        type=float,
        default=DEFAULT_EXPAND_THRESHOLD,
        help=f"expand nodes with at least this fraction (default {DEFAULT_EXPAND_THRESHOLD})",
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
    parser.add_argument(
        "--region-rule",
        choices=(*REGION_RULES, AUTO),
        default=AUTO,
        help="which path the tree and BiSECt try to prove: the most probable (probability, the paper's), "
        "the most probable per expected check (per_check), or auto (default): each validated with its own "
        "eta and kappa, the paper's kept unless per_check needs fewer checks",
    )


def _tree_kwargs(args: argparse.Namespace) -> dict[str, Any]:
    return {
        "expand_threshold": args.threshold,
        "colouring": args.colouring,
        "top_regions": args.top_regions,
        "max_prob_region": args.candidates == "max-prob-region",
        "region_rule": DEFAULT_REGION_RULE if args.region_rule == AUTO else args.region_rule,
    }


def _region_rules(args: argparse.Namespace) -> tuple[str, ...]:
    """The region rules to validate: every one for ``--region-rule auto``, else the one given."""
    return REGION_RULES if args.region_rule == AUTO else (args.region_rule,)


def _eta_arg(text: str) -> float | None:
    """``--eta``: 'auto' (None: validate per dataset) or a number in (0, 1]."""
    if text.strip().lower() == "auto":
        return None
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected 'auto' or a number in (0, 1], got {text!r}") from None
    if not 0.0 < value <= 1.0:
        raise argparse.ArgumentTypeError(f"eta must lie in (0, 1], got {value}")
    return value


def _kappa_arg(text: str) -> tuple[float | None, ...]:
    """``--kappa``: 'auto' (validate among the defaults), 'none' (fixed leaf bias) or a number > 0."""
    from drd_planner.core.switch_threshold import DEFAULT_PSEUDO_COUNTS

    word = text.strip().lower()
    if word == "auto":
        return DEFAULT_PSEUDO_COUNTS
    if word == "none":
        return (None,)
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected 'auto', 'none' or a number > 0, got {text!r}") from None
    if not (value > 0 and math.isfinite(value)):
        raise argparse.ArgumentTypeError(f"kappa must be a positive number of worlds, got {value}")
    return (value,)


def _prior_leaf(problem: Problem, args: argparse.Namespace) -> PriorLeaf:
    """A prior's eta, kappa and region rule: as given, or validated on random queries (``planner.leaf_validation``)."""
    from drd_planner.planner.leaf_validation import leaf_from_options

    return leaf_from_options(
        problem,
        eta=args.eta,
        pseudo_counts=_kappas(args),
        seed=args.seed,
        region_rules=_region_rules(args),
        progress=None,
    )


def _tree_leaf(problem: Problem, args: argparse.Namespace) -> TreeLeaf:
    """A precomputed tree's own eta, kappa and region rule, validated on its query (``planner.leaf_validation``)."""
    from drd_planner.planner.leaf_validation import tree_leaf_from_options

    return tree_leaf_from_options(
        problem,
        eta=args.eta,
        pseudo_counts=_kappas(args),
        seed=args.seed,
        tree_options=_tree_kwargs(args),
        region_rules=_region_rules(args),
        progress=None,
    )


def cmd_build_tree(args: argparse.Namespace) -> int:
    """``drd build-tree``: write a world prior with the dataset's DiRECt tree and any ``--query`` trees."""
    from drd_planner.planner.commands import cmd_build_tree as build

    return build(args, tree_options=_tree_kwargs(args), leaf=_prior_leaf, tree_leaf=_tree_leaf)


def _sizes(text: str) -> tuple[int, ...]:
    try:
        return tuple(int(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated integers, got {text!r}") from None


def _suite_options(args: argparse.Namespace) -> SuiteOptions:
    from drd_planner.bench.runner import DEFAULT_POLICIES
    from drd_planner.bench.stats import TIE_SUBSET
    from drd_planner.bench.suite import SuiteOptions

    return SuiteOptions(
        policies=tuple(args.policies) if args.policies else DEFAULT_POLICIES,
        seed=args.seed,
        eta=args.eta,
        pseudo_counts=_kappas(args),
        max_worlds=args.max_worlds,
        max_checks=args.max_checks,
        tree_options=_tree_kwargs(args),
        validation_folds=args.validation_folds,
        region_rules=() if args.tree else _region_rules(args),
        reference=args.reference,
        tie_subset=tuple(args.tie_subset) if args.tie_subset is not None else TIE_SUBSET,
        resamples=args.resamples,
        figures=Path(args.figures) if args.figures else None,
        training_sizes=args.training_sizes,
        figure_world=args.figure_world,
    )


def cmd_bench(args: argparse.Namespace) -> int:
    """``drd bench``: every policy on every test world of one dataset (``--gccd``/``--dataset``) or all (``--all``)."""
    from drd_planner.bench.runner import check_policy_names, write_bench_files
    from drd_planner.bench.suite import (
        costs_figure,
        run_suite,
        suite_json,
        suite_markdown,
    )

    if args.check_cost_ms is not None and args.queries is None:
        raise DrdError("--check-cost-ms times random queries: give --queries N too")
    if args.queries is not None:
        from drd_planner.bench.query_cli import cmd_bench_queries

        return cmd_bench_queries(args, leaf=_prior_leaf, tree_options=_tree_kwargs(args))
    options = _suite_options(args)
    check_policy_names(options.policies)
    for name, value in (("--max-worlds", args.max_worlds), ("--max-checks", args.max_checks)):
        if value is not None and value < 1:
            raise DrdError(f"{name} must be at least 1, got {value}")
    if args.all:
        if args.tree:
            raise DrdError("--tree fits one dataset and cannot be used with --all")
        suite = run_suite(args.all, options)
        figures = costs_figure(suite.runs, options)
        doc = suite_json(suite, options, figures=figures)
    else:
        suite, figures, doc = _bench_one_dataset(args, options)
    report = suite_markdown(suite, options)
    _print_bench(report, suite)
    write_bench_files(doc, report, json_path=args.json, markdown_path=args.markdown)
    if options.figures is not None:
        count = sum(len(r.figures) for r in suite.runs) + len(figures)
        print(f"wrote {count} figure files under {options.figures}")
    validation = sum(run.leaf.seconds for run in suite.runs if run.leaf is not None)
    print(f"total wall time {suite.seconds:.1f} s (eta and kappa validation {validation:.1f} s of it)")
    return 0


def _print_episode(problem: Problem, result: EpisodeResult) -> None:
    graph = problem.graph
    for k, rec in enumerate(result.checks):
        ends = None
        if graph is not None:
            u, v = graph.edges[rec.edge]
            ends = (int(u), int(v))
        print_check(k + 1, rec.edge, ends, rec.free, rec.stage)
    if result.success and result.path_edges is not None:
        which = "graph path" if result.path_index is None else f"path {result.path_index}"
        print(f"  -> {which} ({result.path_edges.size} edges) verified free after {result.num_checks} checks")
    else:
        print(f"  -> {result.status.value} after {result.num_checks} checks")


def cmd_demo(args: argparse.Namespace) -> int:
    """``drd demo``: generate a planar problem, build a tree, plan on a few held-out worlds."""
    from drd_planner.bench.runner import run_benchmark
    from drd_planner.core.bisect import bias_from_worlds
    from drd_planner.core.episode import TableOracle, run_episode
    from drd_planner.core.policies import POLICIES, PolicyContext
    from drd_planner.core.tree import build_tree
    from drd_planner.data.planar_problem import make_planar_problem

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


def _kappa_option(p: argparse.ArgumentParser) -> None:
    """``--kappa``: the posterior leaf's pseudo-count; unset (None) means 'auto'."""
    p.add_argument(
        "--kappa",
        type=_kappa_arg,
        default=None,
        help="pseudo-count (in worlds) of the posterior leaf that keeps re-conditioning BiSECt's bias on the "
        "training worlds after the switch; 'none' keeps the paper's fixed leaf bias; 'auto' (default) "
        "validates it together with eta",
    )


def _bench_one_dataset(args: argparse.Namespace, options: Any) -> tuple[Any, list[Path], dict[str, Any]]:
    """``drd bench`` on one dataset (``--gccd``/``--dataset``, with ``--tree``): (suite, figures, JSON doc)."""
    from drd_planner.bench.suite import SuiteResult, costs_figure, dataset_json, run_dataset
    from drd_planner.data.dataset_cli import load_problem_from_args, problem_domain
    from drd_planner.data.tree_file import check_bundle_fits
    from drd_planner.planner.prior_file import load_tree_bundle

    problem = load_problem_from_args(args)
    tree = None
    if args.tree:
        bundle = load_tree_bundle(args.tree, expected_domain=problem_domain(problem))
        check_bundle_fits(bundle, problem)
        tree = bundle.tree
        if options.eta is None:  # the settings stored with the tree, unless --eta/--kappa say otherwise
            options = dataclasses.replace(options, eta=bundle.eta)
        if args.kappa is None:
            options = dataclasses.replace(options, pseudo_counts=(bundle.pseudo_count,))
    run = run_dataset(problem, options, tree=tree)
    suite = SuiteResult([run], [], run.seconds)
    figures = list(costs_figure(suite.runs, options))
    doc = dataset_json(run, options)
    doc["figures"] += [str(p) for p in figures]
    return suite, figures, doc


def _print_bench(report: str, suite: Any) -> None:
    """The markdown report, then skipped datasets, notes and the validated leaf settings."""
    from drd_planner.bench.suite import leaf_lines

    print(report, end="")
    for name, reason in suite.skipped:
        print(f"skipped {name}: {reason}")
    for run in suite.runs:
        for note in run.notes:
            print(f"note: {note}")
    for line in leaf_lines(suite.runs):
        print(line)


def _kappas(args: argparse.Namespace) -> tuple[float | None, ...]:
    """The ``--kappa`` candidates (the validated defaults when not given)."""
    from drd_planner.core.switch_threshold import DEFAULT_PSEUDO_COUNTS

    return DEFAULT_PSEUDO_COUNTS if args.kappa is None else tuple(args.kappa)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``drd``."""
    from drd_planner.data.dataset_cli import add_build_dataset_parser

    parser = argparse.ArgumentParser(prog="drd", description="DiRECt + BiSECt active edge evaluation.")
    parser.add_argument("--version", action="version", version=f"drd_planner {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    add_build_dataset_parser(sub)
    _add_build_tree_parser(sub)
    _add_bench_parser(sub)
    add_plan_parser(sub)
    p = sub.add_parser("demo", help="self-contained demo on a generated planar problem")
    p.add_argument("--model", default="one_wall", choices=PLANAR_WORLD_MODELS, help="planar world model")
    p.add_argument("--worlds", type=int, default=300)
    p.add_argument("--episodes", type=int, default=3)
    p.add_argument("--seed", type=int, default=0)
    p.set_defaults(func=cmd_demo)
    return parser


def _add_build_tree_parser(sub: Any) -> None:
    """The ``build-tree`` subcommand."""
    from drd_planner.planner.commands import query_arg

    p = sub.add_parser(
        "build-tree", help="write a world prior (any query) with the dataset's DiRECt tree and --query trees"
    )
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument("--gccd", metavar="DIR", help="authors'-format dataset folder")
    source.add_argument("--dataset", metavar="FILE", help="dataset file written by drd build-dataset")
    source.add_argument("--prior", metavar="FILE", help="add --query trees to this prior file")
    p.add_argument("--out", required=True, help="prior file to write (.npz)")
    p.add_argument(
        "--query",
        type=query_arg,
        action="append",
        default=None,
        metavar="START,GOAL",
        help="also precompute a tree for this query: vertex ids, or states as space-separated numbers "
        "(repeatable)",
    )
    p.add_argument(
        "--eta",
        type=_eta_arg,
        default=None,
        help="switch threshold stored in the file; 'auto' (default) validates it on held-out training worlds",
    )
    _kappa_option(p)
    p.add_argument("--seed", type=int, default=0, help="seed of the validation hold-out")
    _tree_options(p)
    p.set_defaults(func=cmd_build_tree)


def _add_bench_parser(sub: Any) -> None:
    """The ``bench`` subcommand."""
    p = sub.add_parser("bench", help="benchmark policies on a dataset's (or every dataset's) test worlds")
    where = p.add_mutually_exclusive_group(required=True)
    where.add_argument("--gccd", metavar="DIR", help="authors'-format dataset folder")
    where.add_argument("--dataset", metavar="FILE", help="dataset file written by drd build-dataset")
    where.add_argument("--all", metavar="DIR", help="run every authors'-format dataset folder under DIR")
    p.add_argument(
        "--policies", type=_policies, default=None, help="comma-separated (default: the Table-1 set)"
    )
    p.add_argument("--json", help="write the results JSON here")
    p.add_argument("--markdown", help="write the markdown report (Table 1 and absolute numbers) here")
    p.add_argument("--figures", metavar="DIR", help="write the figures (PNG + SVG) into DIR")
    p.add_argument("--tree", help="use this tree file instead of building one (not with --all)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument(
        "--eta",
        type=_eta_arg,
        default=None,
        help="switch to BiSECt at or below this consistent fraction; 'auto' (default) validates it on "
        "held-out training worlds",
    )
    p.add_argument(
        "--validation-folds",
        type=int,
        default=1,
        metavar="K",
        help="validate eta and kappa on K disjoint held-out sets of training worlds, each with its own "
        "tree, and take the simplest setting within one standard error of the best (default 1: one split)",
    )
    _kappa_option(p)
    p.add_argument(
        "--max-worlds",
        type=int,
        default=None,
        help="only the first K test worlds, and at most K held-out training worlds to validate eta and kappa",
    )
    p.add_argument("--max-checks", type=int, default=None, help="cap on checks per episode (failure)")
    p.add_argument("--reference", default="direct_bisect", help="policy the relative costs are over")
    p.add_argument(
        "--tie-subset", type=_policies, default=None, help="tie-filter policies (default: Table-1 subset)"
    )
    p.add_argument("--resamples", type=int, default=2000, help="bootstrap resamples of the mean's CI")
    p.add_argument(
        "--training-sizes",
        type=_sizes,
        default=(50, 100, 200, 450, 900),
        help="training sizes of the checks-vs-training-size figure ('' for none)",
    )
    p.add_argument("--figure-world", type=int, default=0, help="test-list position drawn in Fig. 3")
    p.add_argument(
        "--queries",
        type=int,
        default=None,
        metavar="N",
        help="N random (start, goal) queries (the dataset's own first) against test worlds, through the "
        "Planner (online library and DiRECt, graph fallback); policies default to "
        "direct_bisect,bisect,lazysp_set,lazysp,check_all",
    )
    p.add_argument(
        "--check-cost-ms",
        default=None,
        metavar="C[,C...]",
        help="with --queries: also time every policy to a verified plan with C ms of CPU added to each check "
        "(per kind: the stored query and new ones; off-graph queries need live worlds: "
        "scripts/experiments/bench_check_cost.py; median and mean CPU and wall ms per C in the JSON's policies.NAME.time_ms.C)",
    )
    _tree_options(p)
    p.set_defaults(func=cmd_bench)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; errors print one line and exit 2."""
    return run_command(build_parser().parse_args(argv))


if __name__ == "__main__":
    raise SystemExit(main())
