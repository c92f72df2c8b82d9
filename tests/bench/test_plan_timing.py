"""Time to a verified plan with live checkers: every counted path was checked free in its own run."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import require_ompl

from drd_planner.bench.ompl_peer import LiveWorlds
from drd_planner.bench.plan_timing import (
    PlanRun,
    RecordingOracle,
    checked_free,
    merge_repeats,
    summarize_plans,
    time_lazysp,
    time_ompl,
    time_planner,
)
from drd_planner.bench.world_recipes import seeded_recipes
from drd_planner.core.episode import run_episode
from drd_planner.core.lazysp import LazySP, LazySPSettings
from drd_planner.domains.arm import ArmDomain
from drd_planner.planner.planner import Planner
from drd_planner.planner.prior import WorldPrior
from drd_planner.planner.result import PlanStatus


class Table:
    """Answers from a row of outcomes (the independent reference)."""

    def __init__(self, row: np.ndarray) -> None:
        self.row = row

    def check(self, edge: int) -> bool:
        return bool(self.row[edge])


def test_recording_oracle_and_checked_free(small_arm: ArmDomain) -> None:
    oracle = RecordingOracle(small_arm.checker(small_arm.make_world("clutter", 1)))
    answers = [oracle.check(e) for e in (0, 1, 0)]
    assert oracle.log == {0: answers[0], 1: answers[1]}
    assert oracle.seconds > 0
    assert checked_free([0, 1], {0: True, 1: True})
    assert not checked_free([0, 1], {0: True})
    assert not checked_free([0], {0: False})
    assert not checked_free([], {})


def test_lazysp_and_direct_bisect_runs_verify_their_paths(small_arm: ArmDomain) -> None:
    graph = small_arm.graph
    edges = np.arange(graph.num_edges)
    rows = np.array([small_arm.checker(small_arm.make_world("clutter", s)).check_many(edges) for s in range(12)])
    prior = WorldPrior("small", "arm", graph, np.ones(graph.num_edges), rows[:10])
    planner = Planner(prior)
    found = 0
    for seed in (10, 11):
        world = small_arm.make_world("clutter", seed)
        lazy = time_lazysp(graph, small_arm.checker(world), (0, 1), model="spheres", world=f"clutter:{seed}")
        reference = run_episode(
            None, graph.lengths, LazySP(graph, 0, 1, LazySPSettings(max_checks=None)), Table(rows[seed])
        )
        assert lazy.checks == reference.num_checks
        assert lazy.method == "lazysp"
        plan = time_planner(planner, small_arm.checker(world), (0, 1), model="spheres", world=f"clutter:{seed}")
        again = planner.plan(0, 1, Table(rows[seed]), policy="direct_bisect")
        assert plan.found == (again.status is PlanStatus.FOUND) == lazy.found
        assert plan.checks == again.num_checks
        assert plan.path_edges == again.edges.tolist()
        for run in (lazy, plan):
            assert run.verified == run.found
            assert run.seconds >= run.check_seconds > 0
            assert all(rows[seed][e] for e in run.path_edges)
        found += plan.found
    assert found >= 1


def test_summary_compares_the_same_worlds() -> None:
    def run(model: str, world: str, seconds: float, verified: bool = True) -> PlanRun:
        return PlanRun("lazysp", model, world, verified, verified, 3, seconds, seconds / 2, [0] if verified else [])

    runs = [
        run("spheres", "a", 0.012),
        run("spheres", "a", 0.500),  # a repeat on a loaded machine
        run("spheres", "a", 0.014),
        run("meshes", "a", 0.020),
        run("spheres", "b", 0.030),
        run("meshes", "b", 0.5, verified=False),  # b is left out of both means
        run("spheres", "c", 0.010),
        run("meshes", "c", 0.040),
    ]
    assert len(merge_repeats(runs)) == 6
    summary = summarize_plans(runs)
    assert list(summary) == ["lazysp"]
    block = summary["lazysp"]
    assert (block["worlds"], block["both_verified"]) == (3, 2)
    assert block["spheres"]["verified"] == 3
    assert block["meshes"]["verified"] == 2
    assert block["spheres"]["ms_mean"] == pytest.approx(11.0)  # a's best 12 ms and c's 10 ms
    assert block["meshes"]["ms_mean"] == pytest.approx(30.0)
    assert block["ratio"] == pytest.approx(30.0 / 11.0)
    assert block["ratio_median"] == pytest.approx((20.0 / 12.0 + 4.0) / 2)


def test_ompl_runs_count_only_paths_checked_free(small_arm: ArmDomain) -> None:
    require_ompl()
    recipes = seeded_recipes("clutter", [10, 11])
    live = LiveWorlds("arm", small_arm.spec(), tuple(recipes))
    runs = time_ompl(small_arm.graph, (0, 1), live, model="spheres", time_limit_s=20.0)
    assert [r.world for r in runs] == ["clutter:10", "clutter:11"]
    for run, recipe in zip(runs, recipes, strict=True):
        row = small_arm.checker(recipe.make(small_arm)).check_many(np.arange(small_arm.graph.num_edges))
        assert run.method == "ompl_lazyprm"
        assert run.verified == run.found
        assert all(row[e] for e in run.path_edges)
        assert run.seconds >= run.check_seconds > 0
