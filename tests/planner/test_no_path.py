"""Why a plan found no path: the configurations by their states, the endpoint rule, what blocks the cut."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from conftest import REPO_ROOT, SHARED_DATA

from drd_planner import Planner, PlanStatus, TableOracle
from drd_planner.core.episode import CheckRecord
from drd_planner.core.graph import ExplicitGraph
from drd_planner.geometry.scene import Scene
from drd_planner.geometry.shapes import Box, Pose
from drd_planner.planner import WorldPrior, load_prior
from drd_planner.planner.no_path import edge_states_of, no_path_reason
from drd_planner.planner.query_graph import QueryGraph
from drd_planner.planning.query_support import rebuild_domain

#: Offset (rad) of an off-graph goal from the prior's goal vertex.
NEAR_GOAL = np.array([0.05, 0.05, 0.0, 0.0, 0.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def shipped() -> tuple[WorldPrior, Any]:
    if not (SHARED_DATA / "panda" / "panda_spherized.urdf").is_file():
        pytest.skip("shared Panda model not present (set DRD_SHARED_DATA)")
    prior = load_prior(REPO_ROOT / "trees" / "arm_table_clutter.npz")
    return prior, rebuild_domain(prior, "arm_table_clutter")


def _goal_in_a_can(prior: WorldPrior, domain: Any) -> tuple[np.ndarray, Scene]:
    goal = prior.graph.vertex_states[1] + NEAR_GOAL
    scene = Scene(margin=0.0)
    scene.add(
        Box([0.15, 0.15, 0.15]), Pose(domain.end_effector_positions(goal[None])[0].tolist()), name="can"
    )
    return goal, scene


def test_a_blocked_goal_state_is_named_with_what_blocks_it(shipped: tuple[WorldPrior, Any]) -> None:
    prior, domain = shipped
    goal, scene = _goal_in_a_can(prior, domain)
    result = Planner(prior, growth=None, snap_tolerance=1e-6).plan(0, goal, domain.scene_checker(scene))
    assert result.status is PlanStatus.NO_PATH
    reason = result.reason
    assert "from the start (vertex 0: [0.5, 0.7, 0.0, -1.6, 0.0, 2.4, 0.785])" in reason
    assert (
        "to the goal [-0.45, 0.75, 0.0, -1.6, 0.0, 2.4, 0.785]" in reason
    )  # an off-graph state: no vertex id
    assert "all 4 edges joining the goal" in reason and "were checked blocked" in reason
    assert "the goal state itself is blocked: scene object 'can' (panda_" in reason
    # With growth, growth checks the goal's state first and stops: no path can exist.
    grown = Planner(prior, snap_tolerance=1e-6).plan(0, goal, domain.scene_checker(scene))
    assert grown.status is PlanStatus.NO_PATH and "can exist" in grown.reason
    assert "goal state itself is blocked (checked): scene object 'can'" in grown.reason


def test_a_walled_in_start_names_the_obstacles_of_its_motions(shipped: tuple[WorldPrior, Any]) -> None:
    prior, domain = shipped
    checker = domain.checker(domain.make_world("table_clutter", 3))
    result = Planner(prior, growth=None).plan(0, 1, checker)
    assert result.status is PlanStatus.NO_PATH
    assert "edges joining the start (vertex 0:" in result.reason
    assert "the start state itself is free, the motions are blocked by scene object" in result.reason


def test_without_an_explainer_the_reason_still_names_the_states() -> None:
    states = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    graph = ExplicitGraph(np.array([[0, 1], [1, 2]]), np.ones(2), 3, vertex_states=states)
    query = QueryGraph(graph, None, np.ones(2), 0, 2)
    log = [CheckRecord(0, 1, False, "graph", 0.0, 0.0)]
    oracle = TableOracle(np.array([True, False]))
    reason = no_path_reason(query, log, oracle, edge_states_of(_prior_of(graph), query, None))
    assert reason.startswith(
        "no free path from the start (vertex 0: [0.0, 0.0]) to the goal (vertex 2: [2.0, 0.0])"
    )
    assert "1 blocked edges disconnect them (1 checks)" in reason
    empty = QueryGraph(
        ExplicitGraph(np.zeros((0, 2), dtype=np.int64), np.zeros(0), 3, vertex_states=states),
        None,
        np.zeros(0),
        0,
        2,
    )
    assert "even with every edge free" in no_path_reason(empty, [], oracle, lambda _e: None)


def _prior_of(graph: ExplicitGraph) -> WorldPrior:
    return WorldPrior(
        name="line",
        domain="planar",
        graph=graph,
        edge_costs=np.ones(graph.num_edges),
        worlds=np.ones((1, graph.num_edges), dtype=bool),
    )
