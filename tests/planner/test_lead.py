"""The lead: a new query's lazy search before its library, for as many checks as the library costs."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drd_planner import Planner, PlanStage, PlanStatus, TableOracle, prior_from_problem
from drd_planner.core.episode import EdgeOracle
from drd_planner.core.problem import Problem
from drd_planner.core.status import PlanCause
from drd_planner.core.tree import build_tree
from drd_planner.core.world_columns import WorldColumns
from drd_planner.exceptions import ProblemError
from drd_planner.planner import QueryTree, WorldPrior
from drd_planner.planner.lead import check_cost, lead_checks
from drd_planner.planner.query_graph import prior_query
from drd_planner.planner.query_model import QueryModel
from drd_planner.planner.query_models import LIBRARY_COST_QUERIES
from drd_planner.planner.roadmap_growth import lazy_search


def _planner(forest_prior: WorldPrior, check_ms: float | None, library_ms: float | None) -> Planner:
    """A planner without the probe (so every check before the library is the lead's)."""
    planner = Planner(forest_prior, probe_probability=None)
    planner.check_cost_ms = check_ms
    planner.set_library_cost_ms(library_ms)
    return planner


def _cases(
    forest_problem: Problem, forest_prior: WorldPrior, count: int, seed: int
) -> list[tuple[int, int, np.ndarray]]:
    """Random vertex queries with a test world in which they have a free path."""
    worlds = forest_problem.require_worlds()
    plain = Planner(forest_prior, probe_probability=None)
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(40 * count):
        s, g = (int(v) for v in rng.choice(forest_prior.graph.num_vertices, size=2, replace=False))
        row = worlds.X[int(rng.choice(worlds.test_ids))]
        if plain.plan(s, g, TableOracle(row)).found:
            out.append((s, g, row))
        if len(out) == count:
            break
    assert len(out) == count
    return out


def _pure_lazy_search(forest_prior: WorldPrior, s: int, g: int, row: np.ndarray, budget: int | None) -> list[int]:
    """The edges the graph stage's lazy search checks on the query from nothing known."""
    assert forest_prior.worlds is not None
    query = prior_query(forest_prior, s, g, WorldColumns(forest_prior.worlds))
    episode = lazy_search(forest_prior, query, TableOracle(row), {}, budget=budget, deadline=None, stage="x")
    return [c.edge for c in episode.checks]


def test_the_lead_budget_is_the_library_price_in_checks() -> None:
    assert lead_checks(None, 10.0) == 0
    assert lead_checks(0.0, 10.0) is None
    assert lead_checks(0.2, 10.0) == 50
    assert lead_checks(0.2, 10.0, 0.3) == 20  # each check costs the lead its own search too
    assert lead_checks(0.0, 10.0, 0.5) == 20  # free checks: the lead's own time alone limits it
    assert lead_checks(None, 10.0, 0.5) == 0
    assert lead_checks(3.0, 10.0) == 3
    assert lead_checks(20.0, 10.0) == 0
    assert check_cost(None, "x") is None
    assert check_cost(2, "x") == 2.0


@pytest.mark.parametrize("bad", [-0.1, math.nan, math.inf])
def test_a_cost_that_is_not_a_finite_non_negative_number_is_refused(forest_prior: WorldPrior, bad: float) -> None:
    planner = Planner(forest_prior)
    with pytest.raises(ProblemError, match="check_cost_ms must be a finite number"):
        planner.check_cost_ms = bad
    with pytest.raises(ProblemError, match="library_cost_ms must be a finite number"):
        planner.set_library_cost_ms(bad)
    assert planner.check_cost_ms is None
    assert planner.lead_checks() == 0


def test_a_lead_that_verifies_a_path_builds_no_library(forest_problem: Problem, forest_prior: WorldPrior) -> None:
    planner = _planner(forest_prior, check_ms=1.0, library_ms=1000.0)
    assert planner.lead_checks() == 1000
    for s, g, row in _cases(forest_problem, forest_prior, 6, seed=1):
        result = planner.plan(s, g, TableOracle(row))
        assert result.status is PlanStatus.FOUND
        assert result.stage is PlanStage.LEAD
        assert {c.stage for c in result.checks} == {"lead"}
        assert [c.edge for c in result.checks] == _pure_lazy_search(forest_prior, s, g, row, None)
        assert row[result.edges].all()
        model = planner.query_model(s, g)
        assert model.library is None
        assert model.library_pending  # never needed, never built


def test_a_lead_that_runs_out_hands_its_outcomes_to_the_library(
    forest_problem: Problem, forest_prior: WorldPrior
) -> None:
    planner = _planner(forest_prior, check_ms=1.0, library_ms=2.5)
    plain = Planner(forest_prior, probe_probability=None)
    assert planner.lead_checks() == 2
    handed = 0
    for s, g, row in _cases(forest_problem, forest_prior, 30, seed=2):
        if len(_pure_lazy_search(forest_prior, s, g, row, None)) <= 2:
            continue
        handed += 1
        result = planner.plan(s, g, TableOracle(row))
        edges = [c.edge for c in result.checks]
        assert len(set(edges)) == len(edges)  # nothing checked twice
        assert edges[:2] == _pure_lazy_search(forest_prior, s, g, row, 2)
        assert [c.stage for c in result.checks[:2]] == ["lead", "lead"]
        assert all(c.stage != "lead" for c in result.checks[2:])
        assert [c.step for c in result.checks] == list(range(len(edges)))
        assert result.status is plain.plan(s, g, TableOracle(row)).status is PlanStatus.FOUND
        assert row[result.edges].all()
        assert all(result.outcomes()[int(e)] for e in result.edges)
        built = planner.query_model(s, g)
        assert built.library is not None
        assert not built.library_pending
        assert result.timings.library_s >= built.build_s  # the library's time counted as such
        if handed >= 5:
            break
    assert handed >= 5


def test_a_lead_that_proves_no_path_ends_the_plan_without_a_library(forest_prior: WorldPrior) -> None:
    planner = _planner(forest_prior, check_ms=0.0, library_ms=1.0)
    assert planner.lead_checks() is None  # checks and the lead's own search cost nothing: it runs until it ends
    s, g = 0, forest_prior.graph.num_vertices - 1
    result = planner.plan(s, g, TableOracle(np.zeros(forest_prior.graph.num_edges, dtype=bool)))
    assert result.status is PlanStatus.NO_PATH
    assert result.num_checks >= 1
    assert {c.stage for c in result.checks} == {"lead"}
    assert planner.query_model(s, g).library is None


def test_no_lead_without_a_check_cost_for_other_policies_or_a_stored_query(forest_problem: Problem) -> None:
    assert forest_problem.start is not None
    assert forest_problem.goal is not None
    qt = QueryTree(
        "own",
        forest_problem.start,
        forest_problem.goal,
        forest_problem.library,
        build_tree(forest_problem, progress=False),
    )
    stored = prior_from_problem(forest_problem, domain="planar", trees=(qt,), eta=1.0)
    worlds = forest_problem.require_worlds()
    row = worlds.X[int(worlds.test_ids[0])]
    unknown = Planner(stored, probe_probability=None)
    told = _planner(stored, check_ms=0.5, library_ms=1000.0)
    assert unknown.lead_checks() == 0
    for s, g in ((qt.start, qt.goal), (1, stored.graph.num_vertices - 2)):
        plain = unknown.plan(s, g, TableOracle(row))
        assert all(c.stage != "lead" for c in plain.checks)
        for policy in ("bisect", "max_tally"):
            result = told.plan(s, g, TableOracle(row), policy=policy)
            assert all(c.stage != "lead" for c in result.checks)
            assert [c.edge for c in result.checks] == [
                c.edge for c in unknown.plan(s, g, TableOracle(row), policy=policy).checks
            ]
    stored_result = told.plan(qt.start, qt.goal, TableOracle(row))  # its tree costs nothing per query
    assert all(c.stage != "lead" for c in stored_result.checks)
    assert [c.edge for c in stored_result.checks] == [
        c.edge for c in unknown.plan(qt.start, qt.goal, TableOracle(row)).checks
    ]


def test_budgets_stop_the_lead(forest_problem: Problem, forest_prior: WorldPrior) -> None:
    planner = _planner(forest_prior, check_ms=1.0, library_ms=1000.0)
    s, g, row = next(
        c
        for c in _cases(forest_problem, forest_prior, 10, seed=3)
        if len(_pure_lazy_search(forest_prior, *c, None)) >= 2
    )
    result = planner.plan(s, g, TableOracle(row), max_checks=1)
    assert result.status is PlanStatus.BUDGET_EXHAUSTED
    assert result.cause is PlanCause.CHECK_BUDGET
    assert [(c.stage, c.edge) for c in result.checks] == [("lead", _pure_lazy_search(forest_prior, s, g, row, 1)[0])]


def test_the_library_price_is_measured_once_per_kind_and_can_be_fixed(forest_prior: WorldPrior) -> None:
    planner = Planner(forest_prior)
    staged = planner._models.price_stage
    assert staged is not None
    timed: list[int] = []

    def stage(model: QueryModel, oracle: EdgeOracle) -> None:  # the buy side: the library stage to its plan
        assert model.library is not None
        timed.append(model.query.goal)
        staged(model, oracle)

    planner._models.price_stage = stage
    planner.warm_up()
    kept = planner._models.search.goals_kept
    measured, own = planner.library_cost_ms(), planner.lead_check_ms()
    assert measured > 0.0
    assert own > 0.0  # the lead's searches were timed on the same queries
    assert (planner.library_cost_ms(), planner.lead_check_ms()) == (measured, own)  # once
    assert planner._models.search.goals_kept == kept  # its searches leave nothing behind
    assert len(timed) == LIBRARY_COST_QUERIES  # each sample query's library stage is part of the price
    planner.set_library_cost_ms(7.0)
    assert planner.library_cost_ms() == planner.library_cost_ms(joined=True) == 7.0
    assert planner.lead_check_ms() == 0.0  # a fixed price: nothing measured
    planner.check_cost_ms = 2.0
    assert planner.lead_checks() == 3
    planner.set_library_cost_ms(7.0, lead_check_ms=1.5)
    assert planner.lead_checks() == 2  # 7 / (2 + 1.5)
    with pytest.raises(ProblemError, match="lead_check_ms must be a finite number"):
        planner.set_library_cost_ms(7.0, lead_check_ms=-1.0)
    with pytest.raises(ProblemError, match="give value too"):
        planner.set_library_cost_ms(None, lead_check_ms=1.0)
    assert planner.lead_checks() == 2  # a refused call changes nothing
    planner.set_library_cost_ms(None)
    assert (planner.library_cost_ms(), planner.lead_check_ms()) == (measured, own)
    assert planner.lead_checks() == math.floor(round(measured / (2.0 + own), 9))


def test_same_price_same_checks(forest_problem: Problem, forest_prior: WorldPrior) -> None:
    first, second = (_planner(forest_prior, check_ms=1.0, library_ms=3.0) for _ in range(2))
    for s, g, row in _cases(forest_problem, forest_prior, 8, seed=4):
        a, b = first.plan(s, g, TableOracle(row), seed=3), second.plan(s, g, TableOracle(row), seed=3)
        assert [c.edge for c in a.checks] == [c.edge for c in b.checks]
        assert a.edges.tolist() == b.edges.tolist()
