"""``drd bench --queries N``: the random-query benchmark from the command line."""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from drd_planner.bench.queries import (
    DEFAULT_QUERY_POLICIES,
    query_markdown,
    run_query_benchmark,
)
from drd_planner.bench.runner import require_test_worlds, write_bench_files
from drd_planner.core.problem import Problem
from drd_planner.core.tree import build_tree
from drd_planner.exceptions import DrdError
from drd_planner.planner.leaf_validation import PriorLeaf
from drd_planner.planner.planner import Planner
from drd_planner.planner.prior import QueryTree, WorldPrior, prior_from_problem
from drd_planner.planner.prior_file import load_prior
from drd_planner.planner.query_sampling import draw_queries

Leaf = Callable[[Problem, argparse.Namespace], PriorLeaf]


def benchmark_prior(
    problem: Problem, args: argparse.Namespace, *, leaf: Leaf, tree_options: dict[str, Any]
) -> tuple[WorldPrior, str]:
    """The prior the query benchmark plans with: ``--tree``'s, or one built from the training worlds."""
    from drd_planner.data.dataset_cli import problem_domain

    domain = problem_domain(problem)
    if args.tree:
        prior = load_prior(args.tree, expected_domain=domain)
        if problem.graph is None or not np.array_equal(prior.graph.edges, problem.graph.edges):
            raise DrdError(f"{args.tree} was built for another graph than {problem.name!r}")
        return prior, (
            f"prior {args.tree} (eta {prior.eta:g}, kappa {prior.pseudo_count}, region rule {prior.region_rule})"
        )
    setting = leaf(problem, args)
    tree = build_tree(problem, progress=False, **{**tree_options, "region_rule": setting.region_rule})
    assert problem.start is not None and problem.goal is not None
    own = QueryTree(problem.name, int(problem.start), int(problem.goal), problem.library, tree)
    prior = prior_from_problem(
        problem,
        domain=domain,
        trees=(own,),
        eta=setting.eta,
        pseudo_count=setting.pseudo_count,
        region_rule=setting.region_rule,
        library_seed=args.seed,
    )
    return prior, setting.note


def cmd_bench_queries(args: argparse.Namespace, *, leaf: Leaf, tree_options: dict[str, Any]) -> int:
    """Run the query benchmark on ``--gccd`` or ``--dataset`` and print (and write) its table."""
    from drd_planner.data.dataset_cli import load_problem_from_args

    if args.all:
        raise DrdError("--queries runs on one dataset (--gccd DIR or --dataset FILE), not --all")
    if args.queries < 1:
        raise DrdError(f"--queries must be at least 1, got {args.queries}")
    if args.max_checks is not None and args.max_checks < 1:
        raise DrdError(f"--max-checks must be at least 1, got {args.max_checks}")
    t0 = time.perf_counter()
    problem = load_problem_from_args(args)
    require_test_worlds(problem)
    prior, note = benchmark_prior(problem, args, leaf=leaf, tree_options=tree_options)
    prepare_s = time.perf_counter() - t0
    planner = Planner(prior)
    queries = draw_queries(problem, args.queries, seed=args.seed)
    policies = tuple(args.policies) if args.policies else DEFAULT_QUERY_POLICIES
    doc = run_query_benchmark(
        problem, planner, queries, policies=policies, seed=args.seed, max_checks=args.max_checks
    )
    doc["settings"]["leaf"] = note
    doc["memory_bytes"] = planner.memory_bytes()
    report = query_markdown(doc)
    print(report, end="")
    print(f"eta, kappa and region rule: {note}")
    write_bench_files(doc, report, json_path=args.json, markdown_path=args.markdown)
    print(
        f"total wall time {time.perf_counter() - t0:.1f} s (loading, eta and kappa and the tree "
        f"{prepare_s:.1f} s, episodes {doc['seconds']:.1f} s)"
    )
    return 0
