"""Roadmap growth: a path where the roadmap has none, every grown edge checked, determinism, budgets, settings."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from drd_planner import Planner, PlanStage, PlanStatus
from drd_planner.exceptions import ProblemError
from drd_planner.planner import WorldPrior, load_prior
from drd_planner.planner.roadmap_growth import DEFAULT_GROWTH, GROWTH_STAGE, GrowthSettings
from drd_planner.planning.prior_domain import rebuild_domain
from drd_planner.planning.scene_plan import path_states
from tests.conftest import REPO_ROOT, SHARED_DATA

#: A Table+Clutter world of the shipped arm prior whose roadmap has no free path from vertex 0 to vertex 1
#: (its own query), while the world has one (found by growth, then checked again below).
CUT_WORLD = 3


@pytest.fixture(scope="module")
def shipped() -> tuple[WorldPrior, Any]:
    if not (SHARED_DATA / "panda" / "panda_spherized.urdf").is_file():
        pytest.skip("shared Panda model not present (set DRD_SHARED_DATA)")
    prior = load_prior(REPO_ROOT / "trees" / "arm_table_clutter.npz")
    return prior, rebuild_domain(prior, "arm_table_clutter")


def _checker(domain: Any, seed: int = CUT_WORLD) -> Any:
    return domain.checker(domain.make_world("table_clutter", seed))


def test_growth_finds_a_path_where_the_roadmap_has_none(shipped: tuple[WorldPrior, Any]) -> None:
    prior, domain = shipped
    without = Planner(prior, growth=None).plan(0, 1, _checker(domain))
    assert without.status is PlanStatus.NO_PATH
    assert without.growth is None
    assert "no free path from the start (vertex 0: [0.5, 0.7" in without.reason  # configurations, not ids only
    result = Planner(prior).plan(0, 1, _checker(domain))
    assert result.found
    assert result.stage is PlanStage.GROW
    growth = result.growth
    assert growth is not None
    assert growth.stop == "path"
    assert growth.rounds >= 1
    assert growth.vertices_added > 0
    assert growth.edges_added > 0
    assert "growth round" in result.reason
    # Every edge of the path was checked free in this plan; the grown ones are motions of the grown graph.
    outcome = result.outcomes()
    assert all(outcome[int(e)] for e in result.edges)
    grown = [int(e) for e in result.edges if e >= prior.graph.num_edges]
    assert grown
    assert all(e in result.motions for e in grown)
    assert {c.stage for c in result.checks if c.edge in grown} == {GROWTH_STAGE}
    # And the whole dense path is free for a fresh checker of the same world (static rules and scene).
    dense = path_states(domain, prior, result)
    assert np.allclose(dense[0], prior.graph.vertex_states[0])
    assert np.allclose(dense[-1], prior.graph.vertex_states[1])
    assert np.abs(np.diff(dense, axis=0)).max() <= domain.resolution + 1e-9
    assert _checker(domain).check_motion(dense)


def test_same_seed_same_checks_same_path(shipped: tuple[WorldPrior, Any]) -> None:
    prior, domain = shipped
    first = Planner(prior).plan(0, 1, _checker(domain), seed=4)
    again = Planner(prior).plan(0, 1, _checker(domain), seed=4)
    assert first.found
    assert again.found
    assert [(c.edge, c.free) for c in first.checks] == [(c.edge, c.free) for c in again.checks]
    assert first.edges.tolist() == again.edges.tolist()
    assert first.growth is not None
    assert again.growth is not None
    np.testing.assert_array_equal(first.growth.query.graph.vertex_states, again.growth.query.graph.vertex_states)


def test_a_growth_budget_ends_with_no_path_and_says_what_was_tried(shipped: tuple[WorldPrior, Any]) -> None:
    prior, domain = shipped
    tiny = GrowthSettings(max_rounds=1, samples_per_round=1, bridges=0)
    result = Planner(prior, growth=tiny).plan(0, 1, _checker(domain))
    assert result.status is PlanStatus.NO_PATH
    assert result.growth is not None
    assert result.growth.stop == "rounds"
    assert result.growth.rounds == 1
    assert "within the growth budget (1 growth round(s) added" in result.reason
    assert "vertex 0: [0.5, 0.7" in result.reason
    assert "vertex 1: [-0.5, 0.7" in result.reason


@pytest.mark.parametrize(("budget", "ran_out"), [({"max_checks": 25}, "check budget"), ({"time_budget_s": 0.05}, "")])
def test_the_plans_budgets_end_growth_with_their_own_status(
    shipped: tuple[WorldPrior, Any], budget: dict[str, Any], ran_out: str
) -> None:
    prior, domain = shipped
    result = Planner(prior).plan(0, 1, _checker(domain), **budget)
    assert result.status is PlanStatus.BUDGET_EXHAUSTED
    assert ran_out in result.reason
    assert "budget ran out" in result.reason
    if "max_checks" in budget:
        assert result.num_checks <= 25
        assert result.growth is not None
        assert result.growth.stop == "plan_checks"


def test_growth_checks_the_ends_first_and_stops_when_one_is_blocked(shipped: tuple[WorldPrior, Any]) -> None:
    prior, domain = shipped
    from drd_planner.geometry.scene import Scene
    from drd_planner.geometry.shapes import Box, Pose

    scene = Scene(margin=0.0)
    goal_tool = domain.end_effector_positions(prior.graph.vertex_states[[1]])[0]
    scene.add(Box([0.15, 0.15, 0.15]), Pose(goal_tool.tolist()), name="can")
    result = Planner(prior).plan(0, 1, domain.scene_checker(scene))
    assert result.status is PlanStatus.NO_PATH
    assert result.growth is not None
    assert result.growth.stop == "goal_blocked"
    assert result.growth.rounds == 0
    assert "can exist" in result.reason
    assert "goal state itself is blocked (checked): scene object 'can'" in (result.reason)


def test_growth_settings_are_checked() -> None:
    assert DEFAULT_GROWTH.seconds is not None
    assert DEFAULT_GROWTH.max_rounds >= 1
    for bad in (
        {"max_rounds": 0},
        {"seconds": -1.0},
        {"start_share": 0.7, "goal_share": 0.7},
        {"sigma_range": (0.5, 0.1)},
        {"reach_fraction": 2.0},
        {"bridges": -1},
        {"max_checks": 0},
        {"max_joins": 0},
        {"join_batch": 0},
        {"graph_checks_first": 0},
    ):
        with pytest.raises(ProblemError):
            GrowthSettings(**bad)
    with pytest.raises(ProblemError, match="graph_checks_first 0"):
        GrowthSettings(graph_checks_first=0)
    assert GrowthSettings(graph_checks_first=None).graph_checks_first is None


def test_a_domain_without_a_sampler_does_not_grow() -> None:
    from drd_planner import TableOracle
    from drd_planner.data.planar_problem import make_planar_problem
    from drd_planner.planner import prior_from_problem

    problem = make_planar_problem(model="forest", num_worlds=60, seed=7)
    prior = prior_from_problem(problem, domain="planar")
    graph = problem.graph
    assert graph is not None
    assert problem.start is not None
    world = np.ones(problem.num_edges, dtype=bool)
    world[(graph.edges == problem.start).any(axis=1)] = False
    result = Planner(prior).plan(problem.start, problem.goal, TableOracle(world))  # type: ignore[arg-type]
    assert result.status is PlanStatus.NO_PATH
    assert result.growth is None
    assert "no free path from the start (vertex" in result.reason
