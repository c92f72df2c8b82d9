"""``drd plan`` on a dataset world as a library call: one plan through :class:`Planner` against a table oracle.

:func:`plan_dataset_world` plans once (:class:`DatasetPlanOptions`) against one world row of a dataset's outcome
matrix and prints the check log and the outcome. The command line that makes the options is
:mod:`drd_planner.cli.plan`; ``drd plan``'s other forms are :mod:`drd_planner.planning.bag_command` and
:mod:`drd_planner.planning.scene_command`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drd_planner.core.episode import TableOracle
from drd_planner.data.problem_source import ProblemSource, problem_domain
from drd_planner.exceptions import DrdError
from drd_planner.planner.endpoints import QueryText, endpoint_value
from drd_planner.planner.planner import Planner
from drd_planner.planner.result import PlanResult

__all__ = ["DatasetPlanOptions", "plan_dataset_world", "print_plan"]


@dataclass(frozen=True)
class DatasetPlanOptions:
    """One ``drd plan`` on a dataset world.

    Attributes:
        prior: the prior (or tree) file to plan with.
        source: the dataset holding the world.
        world: the 0-based world row to plan against (None: refused, the world must be chosen).
        query: the query to plan (start and goal text, :data:`~drd_planner.planner.endpoints.QueryText`; None:
            the dataset's own).
        max_checks: end the plan after this many checks (None: no cap).
        policy: the library stage's policy (:data:`~drd_planner.planner.planner.PLAN_POLICIES`).
        seed: the policy's seed.
    """

    prior: str
    source: ProblemSource
    world: int | None = None
    query: QueryText | None = None
    max_checks: int | None = None
    policy: str = "direct_bisect"
    seed: int = 0


def plan_dataset_world(options: DatasetPlanOptions) -> int:
    """``drd plan --gccd/--dataset``: one plan through :class:`Planner` against one dataset world (a table oracle).

    Prints the check log and the outcome; returns 0 when a path was found, 1 otherwise.
    """
    if options.world is None:
        raise DrdError("--world is required with --gccd / --dataset")
    problem = options.source.load()
    planner = Planner.from_file(options.prior, expected_domain=problem_domain(problem))
    graph = problem.graph
    if graph is None or not np.array_equal(planner.prior.graph.edges, graph.edges):
        raise DrdError(f"{options.prior} was built for another graph than {problem.name!r}")
    worlds = problem.require_worlds()
    if not 0 <= options.world < worlds.num_worlds:
        raise DrdError(f"--world must lie in [0, {worlds.num_worlds})")
    if planner.prior.name != problem.name:
        print(f"note: the prior was built from {planner.prior.name}; planning on a world of {problem.name}")
    if options.world in set(worlds.train_ids.tolist()):
        print(
            f"note: world {options.world} is a training world (the prior has seen it); test worlds: "
            f"{', '.join(str(w) for w in worlds.test_ids[:8].tolist())}, ..."
        )
    start, goal = (
        (problem.start, problem.goal)
        if options.query is None
        else (
            endpoint_value(options.query[0]),
            endpoint_value(options.query[1]),
        )
    )
    assert start is not None and goal is not None
    result = planner.plan(
        start,
        goal,
        TableOracle(worlds.X[options.world]),
        seed=options.seed,
        max_checks=options.max_checks,
        policy=options.policy,
    )
    print_plan(planner, result)
    return 0 if result.found else 1


def print_plan(planner: Planner, result: PlanResult) -> None:
    """The check log and the outcome of one plan, one line each."""
    edges = planner.prior.graph.edges
    for k, rec in enumerate(result.checks):
        u, v = (int(x) for x in edges[rec.edge])
        state = "free   " if rec.free else "BLOCKED"
        ends = f"({u}->{v})"
        print(f"  check {k + 1:3d}: edge {rec.edge:5d} {ends:14s}{state} [{rec.stage}]")
    t = result.timings
    print(
        f"  -> {result.status.value}: {result.reason} [query {result.query or '-'}, "
        f"stage {result.stage.value if result.stage else '-'}; library {t.library_s * 1e3:.1f} ms, "
        f"selection {t.selection_s * 1e3:.1f} ms, checks {t.checks_s * 1e3:.1f} ms]"
    )
