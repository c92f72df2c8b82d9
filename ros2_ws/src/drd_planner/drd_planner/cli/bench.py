"""``drd bench``: its flags, made into the options of a benchmark run.

:class:`~drd_planner.bench.bench_command.BenchOptions`, or with ``--queries N``
:class:`~drd_planner.bench.query_command.QueryBenchOptions`.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from drd_planner.cli.argtypes import add_prior_option, eta_arg, int_list, name_list
from drd_planner.cli.shared_flags import (
    add_kappa_option,
    add_tree_options,
    kappas,
    leaf_choice,
    problem_source,
    region_rules,
    tree_settings,
)
from drd_planner.exceptions import DrdError

if TYPE_CHECKING:
    from drd_planner.bench.suite import SuiteOptions

__all__ = ["add_bench_parser", "cmd_bench", "suite_options"]


def suite_options(args: argparse.Namespace) -> SuiteOptions:
    """The benchmark settings of the parsed ``bench`` flags."""
    from drd_planner.bench.runner import DEFAULT_POLICIES
    from drd_planner.bench.stats import TIE_SUBSET
    from drd_planner.bench.suite import SuiteOptions

    return SuiteOptions(
        policies=tuple(args.policies) if args.policies else DEFAULT_POLICIES,
        seed=args.seed,
        eta=args.eta,
        pseudo_counts=kappas(args),
        max_worlds=args.max_worlds,
        max_checks=args.max_checks,
        tree_options=tree_settings(args).kwargs(),
        validation_folds=args.validation_folds,
        region_rules=() if args.prior else region_rules(args),
        reference=args.reference,
        tie_subset=tuple(args.tie_subset) if args.tie_subset is not None else TIE_SUBSET,
        resamples=args.resamples,
        figures=Path(args.figures) if args.figures else None,
        training_sizes=args.training_sizes,
        figure_world=args.figure_world,
    )


def cmd_bench(args: argparse.Namespace) -> int:
    """``drd bench``: every policy on every test world of one dataset (``--gccd``/``--dataset``) or all (``--all``)."""
    from drd_planner.bench.bench_command import BenchOptions, run_bench

    if args.check_cost_ms is not None and args.queries is None:
        raise DrdError("--check-cost-ms times random queries: give --queries N too")
    if args.repeat != 1 and args.check_cost_ms is None:
        raise DrdError("--repeat repeats the episodes timed at check costs: give --check-cost-ms too")
    if args.queries is not None:
        return _bench_queries(args)
    return run_bench(
        BenchOptions(
            suite=suite_options(args),
            source=None if args.all else problem_source(args),
            all_root=args.all,
            prior=args.prior,
            kappa_given=args.kappa is not None,
            json=args.json,
            markdown=args.markdown,
        )
    )


def _bench_queries(args: argparse.Namespace) -> int:
    """``drd bench --queries N``."""
    from drd_planner.bench.query_command import QueryBenchOptions, run_query_bench

    if args.all:
        raise DrdError("--queries runs on one dataset (--gccd DIR or --dataset FILE), not --all")
    return run_query_bench(
        QueryBenchOptions(
            source=problem_source(args),
            queries=args.queries,
            prior=args.prior,
            policies=tuple(args.policies) if args.policies else None,
            check_cost_ms=args.check_cost_ms,
            max_checks=args.max_checks,
            seed=args.seed,
            repeat=args.repeat,
            json=args.json,
            markdown=args.markdown,
            leaf=leaf_choice(args),
            tree=tree_settings(args),
        )
    )


def add_bench_parser(sub: Any) -> argparse.ArgumentParser:
    """Register ``bench`` on an ``add_subparsers()`` object; returns the new parser."""
    p: argparse.ArgumentParser = sub.add_parser(
        "bench", help="benchmark policies on a dataset's (or every dataset's) test worlds"
    )
    where = p.add_mutually_exclusive_group(required=True)
    where.add_argument("--gccd", metavar="DIR", help="authors'-format dataset folder")
    where.add_argument("--dataset", metavar="FILE", help="dataset file written by drd build-dataset")
    where.add_argument("--all", metavar="DIR", help="run every authors'-format dataset folder under DIR")
    p.add_argument("--policies", type=name_list, default=None, help="comma-separated (default: the Table-1 set)")
    p.add_argument("--json", help="write the results JSON here")
    p.add_argument("--markdown", help="write the markdown report (Table 1 and absolute numbers) here")
    p.add_argument("--figures", metavar="DIR", help="write the figures (PNG + SVG) into DIR")
    add_prior_option(p, help="use this prior or tree file instead of building one (not with --all; --tree: deprecated)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument(
        "--eta",
        type=eta_arg,
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
    add_kappa_option(p)
    p.add_argument(
        "--max-worlds",
        type=int,
        default=None,
        help="only the first K test worlds, and at most K held-out training worlds to validate eta and kappa",
    )
    p.add_argument("--max-checks", type=int, default=None, help="cap on checks per episode (failure)")
    p.add_argument("--reference", default="direct_bisect", help="policy the relative costs are over")
    p.add_argument("--tie-subset", type=name_list, default=None, help="tie-filter policies (default: Table-1 subset)")
    p.add_argument("--resamples", type=int, default=2000, help="bootstrap resamples of the mean's CI")
    p.add_argument(
        "--training-sizes",
        type=int_list,
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
        "scripts/experiments/bench_check_cost.py; median and mean CPU and wall ms per C in the JSON's "
        "policies.NAME.time_ms.C)",
    )
    p.add_argument(
        "--repeat",
        type=int,
        default=1,
        metavar="R",
        help="with --check-cost-ms: run each timed episode R times and keep the run of median CPU time "
        "(the same checks each time; less clock noise in the medians)",
    )
    add_tree_options(p)
    p.set_defaults(func=cmd_bench)
    return p
