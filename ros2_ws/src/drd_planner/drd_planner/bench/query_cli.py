"""``drd bench --queries N``: the random-query benchmark from the command line."""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from drd_planner.bench.check_cost import cost_key, parse_check_costs
from drd_planner.bench.cost_bench import (
    check_cost_policies,
    cost_markdown,
    run_cost_episodes,
    summarize_costs,
)
from drd_planner.bench.cost_episodes import CostQuery
from drd_planner.bench.queries import (
    DEFAULT_QUERY_POLICIES,
    query_markdown,
    run_query_benchmark,
)
from drd_planner.bench.runner import require_test_worlds, write_bench_files
from drd_planner.core.episode import TableOracle
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
    costs = parse_check_costs(args.check_cost_ms) if getattr(args, "check_cost_ms", None) is not None else ()
    policies = tuple(args.policies) if args.policies else DEFAULT_QUERY_POLICIES
    if costs:
        check_cost_policies(policies)
    t0 = time.perf_counter()
    problem = load_problem_from_args(args)
    require_test_worlds(problem)
    prior, note = benchmark_prior(problem, args, leaf=leaf, tree_options=tree_options)
    prepare_s = time.perf_counter() - t0
    planner = Planner(prior)
    queries = draw_queries(problem, args.queries, seed=args.seed)
    doc = run_query_benchmark(
        problem, planner, queries, policies=policies, seed=args.seed, max_checks=args.max_checks
    )
    doc["settings"]["leaf"] = note
    doc["memory_bytes"] = planner.memory_bytes()
    report = query_markdown(doc)
    if costs:
        report += time_at_check_costs(problem, prior, queries, doc, costs, policies=policies, seed=args.seed)
    print(report, end="")
    print(f"eta, kappa and region rule: {note}")
    write_bench_files(doc, report, json_path=args.json, markdown_path=args.markdown)
    print(
        f"total wall time {time.perf_counter() - t0:.1f} s (loading, eta and kappa and the tree "
        f"{prepare_s:.1f} s, episodes {doc['seconds']:.1f} s)"
    )
    return 0


#: Why a dataset's test worlds (rows of X) cannot be asked off-graph queries.
OFF_GRAPH_NOTE = (
    "off-graph queries do not apply here: the test worlds are rows of X, which answer graph edges only "
    "(no domain model checks a motion off the graph); scripts/experiments/bench_check_cost.py runs them on live worlds"
)


def time_at_check_costs(
    problem: Problem,
    prior: WorldPrior,
    queries: list[tuple[int, int]],
    doc: dict[str, Any],
    costs: tuple[float, ...],
    *,
    policies: tuple[str, ...],
    seed: int,
) -> str:
    """``--check-cost-ms``: time the queries again at each cost (a fresh planner), into ``doc``; the report.

    The dataset's own query (the first) is the stored kind, the others new; query i runs against test
    world i mod (number of test worlds), as the check benchmark does.
    """
    worlds = problem.require_worlds()
    test = worlds.test_ids
    own = problem.start is not None and problem.goal is not None
    timed_queries = [
        CostQuery("stored" if i == 0 and own else "new", s, g, i % test.size)
        for i, (s, g) in enumerate(queries)
    ]

    def oracle_of(world: int) -> TableOracle:
        return TableOracle(worlds.X[int(test[world])])

    episodes = run_cost_episodes(
        Planner(prior), timed_queries, oracle_of, costs, policies=policies, seed=seed
    )
    summary = summarize_costs(episodes, costs)
    for name, block in summary.items():
        entry = doc["policies"].setdefault(name, {})
        entry["time_ms"] = block["time_ms"]
        entry["time_checks"] = block["checks"]
        entry["time_verified"] = block["verified"]
    doc["check_cost"] = {
        "costs_ms": [cost_key(c) for c in costs],
        "clock": "CPU of this process (time.process_time), wall beside; ms",
        "compared": "per kind, the queries every policy verified at every cost",
        "off_graph": OFF_GRAPH_NOTE,
    }
    return cost_markdown(
        summary, costs, title=f"{problem.name}: time to a verified plan", notes=(OFF_GRAPH_NOTE,)
    )
