"""``drd bench --queries N``: the random-query benchmark, as a library call (:func:`run_query_bench`)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from drd_planner.bench.check_cost import cost_key, parse_check_costs
from drd_planner.bench.cost_bench import (
    CostRun,
    check_cost_policies,
    cost_markdown,
    episode_records,
    run_cost_episodes,
    summarize_costs,
)
from drd_planner.bench.cost_episodes import LEAD_POLICY, CostQuery
from drd_planner.bench.queries import (
    DEFAULT_QUERY_POLICIES,
    query_markdown,
    run_query_benchmark,
)
from drd_planner.bench.runner import require_test_worlds, write_bench_files
from drd_planner.core.episode import TableOracle
from drd_planner.core.problem import Problem
from drd_planner.core.tree import build_tree
from drd_planner.data.problem_source import ProblemSource, problem_domain
from drd_planner.exceptions import DrdError
from drd_planner.planner.build_settings import LeafChoice, TreeSettings
from drd_planner.planner.planner import Planner
from drd_planner.planner.prior import QueryTree, WorldPrior, prior_from_problem
from drd_planner.planner.prior_file import load_prior
from drd_planner.planner.query_sampling import draw_queries


@dataclass(frozen=True)
class QueryBenchOptions:
    """One ``drd bench --queries N`` run.

    Attributes:
        source: the dataset (one; ``--all`` is refused by the command line).
        queries: how many random (start, goal) queries to draw (the dataset's own first; at least 1).
        prior: plan with this prior file (None: build one from the training worlds).
        policies: the policies to run (None: :data:`~drd_planner.bench.queries.DEFAULT_QUERY_POLICIES`).
        check_cost_ms: also time every policy with these milliseconds of CPU added to each check, as
            comma-separated text (:func:`~drd_planner.bench.check_cost.parse_check_costs`; None: no timing).
        max_checks: per-episode check cap (None: none; at least 1).
        seed: the seed of the queries, the episodes and the prior's validation and library.
        repeat: with ``check_cost_ms``, runs of each timed episode, the run of median CPU time kept (at least 1).
        json: write the results JSON here (None: not written).
        markdown: write the markdown report here (None: not written).
        leaf: how the built prior's eta, kappa and region rule are chosen.
        tree: how the built prior's tree is grown.
    """

    source: ProblemSource
    queries: int
    prior: str | None = None
    policies: tuple[str, ...] | None = None
    check_cost_ms: str | None = None
    max_checks: int | None = None
    seed: int = 0
    repeat: int = 1
    json: str | None = None
    markdown: str | None = None
    leaf: LeafChoice = field(default_factory=LeafChoice)
    tree: TreeSettings = field(default_factory=TreeSettings)


def benchmark_prior(problem: Problem, options: QueryBenchOptions) -> tuple[WorldPrior, str]:
    """The prior the query benchmark plans with: ``options.prior``'s, or one built from the training worlds."""
    domain = problem_domain(problem)
    if options.prior:
        prior = load_prior(options.prior, expected_domain=domain)
        if problem.graph is None or not np.array_equal(prior.graph.edges, problem.graph.edges):
            raise DrdError(f"{options.prior} was built for another graph than {problem.name!r}")
        return prior, (
            f"prior {options.prior} (eta {prior.eta:g}, kappa {prior.pseudo_count}, region rule {prior.region_rule})"
        )
    setting = options.leaf.prior_leaf(problem)
    tree = build_tree(problem, progress=False, **{**options.tree.kwargs(), "region_rule": setting.region_rule})
    assert problem.start is not None and problem.goal is not None
    own = QueryTree(problem.name, int(problem.start), int(problem.goal), problem.library, tree)
    prior = prior_from_problem(
        problem,
        domain=domain,
        trees=(own,),
        eta=setting.eta,
        pseudo_count=setting.pseudo_count,
        region_rule=setting.region_rule,
        library_seed=options.seed,
    )
    return prior, setting.note


def run_query_bench(options: QueryBenchOptions) -> int:
    """Run the query benchmark on one dataset and print (and write) its table; exit status 0."""
    if options.queries < 1:
        raise DrdError(f"--queries must be at least 1, got {options.queries}")
    if options.max_checks is not None and options.max_checks < 1:
        raise DrdError(f"--max-checks must be at least 1, got {options.max_checks}")
    if options.repeat < 1:
        raise DrdError(f"--repeat must be at least 1, got {options.repeat}")
    costs = parse_check_costs(options.check_cost_ms) if options.check_cost_ms is not None else ()
    policies = options.policies or DEFAULT_QUERY_POLICIES
    if costs:
        check_cost_policies(policies)
    elif LEAD_POLICY in policies:
        raise DrdError(f"{LEAD_POLICY} is direct_bisect told the check cost: give --check-cost-ms too")
    t0 = time.perf_counter()
    problem = options.source.load()
    require_test_worlds(problem)
    prior, note = benchmark_prior(problem, options)
    prepare_s = time.perf_counter() - t0
    planner = Planner(prior)
    queries = draw_queries(problem, options.queries, seed=options.seed)
    checked = tuple(p for p in policies if p != LEAD_POLICY)  # its checks are direct_bisect's but for the lead
    doc = run_query_benchmark(
        problem, planner, queries, policies=checked, seed=options.seed, max_checks=options.max_checks
    )
    doc["settings"]["leaf"] = note
    doc["memory_bytes"] = planner.memory_bytes()
    report = query_markdown(doc)
    if costs:
        run = CostRun(policies=policies, seed=options.seed, repeat=options.repeat)
        report += time_at_check_costs(problem, prior, queries, doc, costs, run)
    print(report, end="")
    print(f"eta, kappa and region rule: {note}")
    write_bench_files(doc, report, json_path=options.json, markdown_path=options.markdown)
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
    run: CostRun,
) -> str:
    """``--check-cost-ms``: time the queries again at each cost (a fresh planner), into ``doc``; the report.

    The dataset's own query (the first) is the stored kind, the others new; query i runs against test
    world i mod (number of test worlds), as the check benchmark does.
    """
    worlds = problem.require_worlds()
    test = worlds.test_ids
    own = problem.start is not None and problem.goal is not None
    timed_queries = [
        CostQuery("stored" if i == 0 and own else "new", s, g, i % test.size) for i, (s, g) in enumerate(queries)
    ]

    def oracle_of(world: int) -> TableOracle:
        return TableOracle(worlds.X[int(test[world])])

    episodes = run_cost_episodes(Planner(prior), timed_queries, oracle_of, costs, run)
    summary = summarize_costs(episodes, costs)
    for name, block in summary.items():
        entry = doc["policies"].setdefault(name, {})
        entry["time_ms"] = block["time_ms"]
        entry["time_checks"] = block["checks"]
        entry["time_checks_at"] = block["checks_at"]
        entry["time_verified"] = block["verified"]
    doc["check_cost"] = {
        "costs_ms": [cost_key(c) for c in costs],
        "clock": "CPU of this process (time.process_time), wall beside; ms",
        "compared": "per kind, the queries every policy verified at every cost",
        "off_graph": OFF_GRAPH_NOTE,
        "episodes": episode_records(episodes),
    }
    return cost_markdown(summary, costs, title=f"{problem.name}: time to a verified plan", notes=(OFF_GRAPH_NOTE,))
