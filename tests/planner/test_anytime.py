"""The anytime improvement: shorter verified paths after the first, within its budget, deterministic."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from drd_planner import Planner, PlanStage, TableOracle, prior_from_problem
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.library import PathLibrary
from drd_planner.core.problem import Problem
from drd_planner.core.tree import build_tree
from drd_planner.core.worlds import WorldDatabase
from drd_planner.data.planar_problem import make_planar_problem
from drd_planner.exceptions import ProblemError
from drd_planner.planner import PlanResult, QueryTree, WorldPrior
from drd_planner.planner.anytime import ImproveBudget, WorldSampler, as_improve_budget
from drd_planner.planner.graph_fallback import posterior_free_probability

# Three routes from 0 to 7: L (edges 0-3, length 8), M (edges 4-6, length 6), S (edges 7-8, length 3).
EDGES = [[0, 1], [1, 2], [2, 3], [3, 7], [0, 4], [4, 5], [5, 7], [0, 6], [6, 7]]
LENGTHS = [2.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0, 1.5, 1.5]
L, M, S = [0, 1, 2, 3], [4, 5, 6], [7, 8]
COST = {"L": 8.0, "M": 6.0, "S": 3.0}


def _world(*free_routes: list[int]) -> list[bool]:
    row = [False] * len(EDGES)
    for route in free_routes:
        for e in route:
            row[e] = True
    return row


def _routes_problem(test_rows: list[list[bool]]) -> Problem:
    # Training worlds: L always free; M free in 12 of 20 (S too in 3 of those), S alone in 3, neither in 5.
    train = [_world(L, M, S)] * 3 + [_world(L, M)] * 9 + [_world(L, S)] * 3 + [_world(L)] * 5
    x = np.array(train + test_rows, dtype=bool)
    library = PathLibrary((np.array(L),), len(EDGES))  # the library knows only the long route
    graph = ExplicitGraph(np.array(EDGES), np.array(LENGTHS), 8)
    worlds = WorldDatabase(x, library.valid_paths(x), np.arange(20), np.arange(20, x.shape[0]))
    return Problem("routes", library, np.ones(len(EDGES)), graph, 0, 7, worlds)


@pytest.fixture(scope="module")
def routes() -> WorldPrior:
    problem = _routes_problem([_world(L, M, S)])
    own = QueryTree("routes", 0, 7, problem.library, build_tree(problem, progress=False))
    return prior_from_problem(problem, domain="planar", trees=(own,))


class CountingOracle(TableOracle):
    """A table oracle that remembers which edges it was asked, in order."""

    def __init__(self, outcomes: list[bool]) -> None:
        super().__init__(outcomes)
        self.asked: list[int] = []

    def check(self, edge: int) -> bool:
        self.asked.append(int(edge))
        return super().check(edge)


def _assert_every_path_was_checked_free(result: PlanResult) -> None:
    """Safety: each recorded path has every edge checked free among the checks made before it."""
    assert result.improvements, "a budgeted FOUND plan records at least its first path"
    for record in result.improvements:
        seen = {c.edge: c.free for c in result.checks[: record.checks_so_far]}
        assert all(seen.get(int(e)) is True for e in record.path_edges)
    assert result.edges.tolist() == result.improvements[-1].path_edges.tolist()
    assert result.cost == pytest.approx(result.improvements[-1].cost)


def test_the_first_path_is_the_long_route_and_the_budget_finds_the_short_one(routes: WorldPrior) -> None:
    planner = Planner(routes)
    first = planner.plan(0, 7, TableOracle(_world(L, M, S)), seed=0)
    assert first.found
    assert first.cost == COST["L"]
    assert first.improvements == ()
    oracle = CountingOracle(_world(L, M, S))
    better = planner.plan(0, 7, oracle, seed=0, improve_budget=20)
    assert better.found
    assert better.cost == COST["S"]
    assert better.stage is PlanStage.IMPROVE
    assert better.edges.tolist() == S
    assert better.vertices.tolist() == [0, 6, 7]
    assert better.improvements[0].cost == COST["L"]
    assert better.improve_stop == "optimal"  # S is the shortest path of the whole graph
    assert [c.edge for c in better.checks] == oracle.asked
    assert [c.edge for c in better.checks[: first.num_checks]] == [c.edge for c in first.checks]
    assert {c.stage for c in better.checks[first.num_checks :]} == {"improve"}
    _assert_every_path_was_checked_free(better)


def test_every_improvement_is_strictly_shorter_and_some_seed_goes_through_the_middle_route(
    routes: WorldPrior,
) -> None:
    planner = Planner(routes)
    costs_seen = []
    for seed in range(12):
        result = planner.plan(0, 7, TableOracle(_world(L, M, S)), seed=seed, improve_budget=20)
        costs = [r.cost for r in result.improvements]
        assert all(b < a for a, b in itertools.pairwise(costs)), costs
        assert [r.checks_so_far for r in result.improvements] == sorted(r.checks_so_far for r in result.improvements)
        _assert_every_path_was_checked_free(result)
        costs_seen.append(costs)
    assert [COST["L"], COST["M"], COST["S"]] in costs_seen  # two improvements in one plan
    assert [COST["L"], COST["S"]] in costs_seen


def test_a_blocked_edge_ends_a_proposal_and_the_next_draw_goes_elsewhere(routes: WorldPrior) -> None:
    world = _world(L, M, S)
    world[5] = False  # the middle route is blocked in this world
    result = Planner(routes).plan(0, 7, TableOracle(world), seed=1, improve_budget=20)
    assert result.cost == COST["S"]
    extra = result.checks[result.improvements[0].checks_so_far :]
    assert [c.edge for c in extra if not c.free] in ([], [5])  # M stops at its blocked edge, if tried
    assert all(world[c.edge] == c.free for c in result.checks)
    _assert_every_path_was_checked_free(result)


@pytest.mark.parametrize("checks", [1, 2, 3])
def test_the_check_budget_is_respected_and_unaffordable_paths_are_not_started(routes: WorldPrior, checks: int) -> None:
    planner = Planner(routes)
    first = planner.plan(0, 7, TableOracle(_world(L, M, S)), seed=0)
    result = planner.plan(0, 7, TableOracle(_world(L, M, S)), seed=0, improve_budget=checks)
    extra = result.num_checks - first.num_checks
    assert extra <= checks
    if checks == 1:  # every shorter route needs at least 2 checks: nothing is started
        assert extra == 0
        assert result.cost == COST["L"]
        assert result.improve_stop == "patience"
        assert result.stage is first.stage
    _assert_every_path_was_checked_free(result)


def test_the_plans_own_max_checks_caps_the_improvement(routes: WorldPrior) -> None:
    planner = Planner(routes)
    first = planner.plan(0, 7, TableOracle(_world(L, M, S)), seed=0)
    result = planner.plan(
        0, 7, TableOracle(_world(L, M, S)), seed=0, max_checks=first.num_checks + 1, improve_budget=50
    )
    assert result.num_checks <= first.num_checks + 1
    assert result.improve_stop in ("plan_checks", "patience")


def test_a_seconds_budget_alone_works(routes: WorldPrior) -> None:
    result = Planner(routes).plan(0, 7, TableOracle(_world(L, M, S)), improve_budget=ImproveBudget(seconds=5.0))
    assert result.cost == COST["S"]
    assert result.improve_stop == "optimal"


def test_a_spent_seconds_budget_stops_before_any_check(routes: WorldPrior) -> None:
    planner = Planner(routes)
    first = planner.plan(0, 7, TableOracle(_world(L, M, S)))
    result = planner.plan(0, 7, TableOracle(_world(L, M, S)), improve_budget=ImproveBudget(seconds=1e-9))
    assert result.improve_stop == "seconds"
    assert result.num_checks == first.num_checks
    assert result.cost == COST["L"]
    assert len(result.improvements) == 1


def test_same_seed_same_result(routes: WorldPrior) -> None:
    runs = [Planner(routes).plan(0, 7, TableOracle(_world(L, M, S)), seed=4, improve_budget=20) for _ in range(2)]
    assert [(c.edge, c.free, c.stage) for c in runs[0].checks] == [(c.edge, c.free, c.stage) for c in runs[1].checks]
    assert [r.path_edges.tolist() for r in runs[0].improvements] == [
        r.path_edges.tolist() for r in runs[1].improvements
    ]


def test_no_budget_is_the_plain_plan(routes: WorldPrior) -> None:
    planner = Planner(routes)
    plain = planner.plan(0, 7, TableOracle(_world(L, M, S)), seed=3)
    again = planner.plan(0, 7, TableOracle(_world(L, M, S)), seed=3, improve_budget=None)
    assert [c.edge for c in plain.checks] == [c.edge for c in again.checks]
    assert again.improvements == ()
    assert again.improve_stop == ""
    assert again.cost == COST["L"]
    assert all(c.stage != "improve" for c in again.checks)


@pytest.mark.parametrize(
    ("budget", "fragment"),
    [
        (0, "int >= 1"),
        (-3, "int >= 1"),
        (True, "improve_budget must be None, an int"),
        (2.5, "improve_budget must be None, an int"),
        ("10", "improve_budget must be None, an int"),
    ],
)
def test_bad_budgets_are_refused_before_any_check(routes: WorldPrior, budget: object, fragment: str) -> None:
    oracle = CountingOracle(_world(L, M, S))
    with pytest.raises(ProblemError, match=fragment):
        Planner(routes).plan(0, 7, oracle, improve_budget=budget)  # type: ignore[arg-type]
    assert oracle.asked == []


@pytest.mark.parametrize(
    ("fields", "fragment"),
    [
        ({}, "needs checks"),
        ({"checks": 0}, "checks must be an int >= 1"),
        ({"checks": 2.0}, "checks must be an int >= 1"),
        ({"seconds": 0.0}, "seconds must be a positive finite number"),
        ({"seconds": float("nan")}, "seconds must be a positive finite number"),
        ({"seconds": float("inf")}, "seconds must be a positive finite number"),
        ({"checks": 5, "patience": 0}, "patience must be an int >= 1"),
        ({"checks": 5, "tail_probability": 1.5}, r"tail_probability must lie in \[0, 1\]"),
    ],
)
def test_bad_improve_budget_fields_are_refused(fields: dict[str, object], fragment: str) -> None:
    with pytest.raises(ProblemError, match=fragment):
        ImproveBudget(**fields)  # type: ignore[arg-type]


def test_an_int_is_a_check_budget() -> None:
    assert as_improve_budget(7) == ImproveBudget(checks=7)
    assert as_improve_budget(np.int64(3)) == ImproveBudget(checks=3)
    assert as_improve_budget(None) is None


@pytest.mark.parametrize("weighted", [False, True])
def test_the_samplers_probabilities_are_the_graph_stages_posterior(weighted: bool) -> None:
    rng = np.random.default_rng(0)
    worlds = rng.random((40, 30)) < 0.6
    weights = rng.uniform(0.5, 2.0, 40) if weighted else None
    outcomes = {3: True, 7: False, 11: True}
    sampler = WorldSampler(
        worlds,
        weights,
        outcomes,
        num_edges=30,
        alpha=0.9,
        pseudo_count=5.0,
        tail_probability=0.1,
        rng=np.random.default_rng(1),
    )
    expected = posterior_free_probability(worlds, weights, outcomes, num_edges=30, alpha=0.9, pseudo_count=5.0)
    np.testing.assert_allclose(sampler.free_probability(), expected)
    np.testing.assert_allclose(sampler.free_probability(np.array([12, 3, 7])), expected[[12, 3, 7]])


def test_draws_come_from_consistent_worlds_or_the_tail_and_keep_every_outcome() -> None:
    rng = np.random.default_rng(2)
    worlds = rng.random((25, 12)) < 0.5
    outcomes = {0: bool(worlds[0, 0]), 1: bool(worlds[0, 1])}
    consistent = [row.tobytes() for row in worlds if row[0] == outcomes[0] and row[1] == outcomes[1]]

    def sampler(tail: float) -> WorldSampler:
        return WorldSampler(
            worlds,
            None,
            outcomes,
            num_edges=12,
            alpha=0.99,
            pseudo_count=20.0,
            tail_probability=tail,
            rng=np.random.default_rng(5),
        )

    database = sampler(0.0)
    assert database.num_consistent == len(consistent)
    assert all(database.draw().tobytes() in consistent for _ in range(30))
    tails = sampler(1.0)
    tail = [tails.draw() for _ in range(40)]
    assert all(d[0] == outcomes[0] and d[1] == outcomes[1] for d in tail)
    assert sum(d.tobytes() not in consistent for d in tail) > 20  # mostly worlds outside the database
    # With no consistent world left every draw is a tail draw.
    empty = WorldSampler(
        worlds[:1],
        None,
        {0: not worlds[0, 0]},
        num_edges=12,
        alpha=0.99,
        pseudo_count=20.0,
        tail_probability=0.0,
        rng=np.random.default_rng(0),
    )
    assert empty.num_consistent == 0
    assert empty.draw()[0] == (not worlds[0, 0])


@pytest.fixture(scope="module")
def planar() -> tuple[Problem, WorldPrior]:
    problem = make_planar_problem(model="forest", num_worlds=200, seed=3)
    return problem, prior_from_problem(problem, domain="planar")


def test_on_a_planar_problem_improvements_are_safe_shorter_and_within_budget(
    planar: tuple[Problem, WorldPrior],
) -> None:
    problem, prior = planar
    worlds = problem.require_worlds()
    planner = Planner(prior)
    improved = 0
    for i, world in enumerate(worlds.test_ids[:12].tolist()):
        row = worlds.X[world]
        first = planner.plan(problem.start, problem.goal, TableOracle(row), seed=i)  # type: ignore[arg-type]
        if not first.found:
            continue
        budget = first.num_checks
        result = planner.plan(problem.start, problem.goal, TableOracle(row), seed=i, improve_budget=budget)  # type: ignore[arg-type]
        assert result.num_checks - first.num_checks <= budget
        assert result.improvements[0].path_edges.tolist() == first.edges.tolist()
        assert result.cost <= first.cost
        assert row[result.edges].all()
        costs = [r.cost for r in result.improvements]
        assert all(b < a for a, b in itertools.pairwise(costs))
        _assert_every_path_was_checked_free(result)
        improved += result.cost < first.cost
    assert improved >= 1
