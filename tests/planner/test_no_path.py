"""Why a plan found no path: the configurations by their states, the endpoint rule, what blocks the cut."""

from __future__ import annotations

import re
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
from drd_planner.planner.cause import PlanCause
from drd_planner.planner.no_path import blocked_end, edge_states_of, no_path_reason
from drd_planner.planner.query_graph import QueryGraph
from drd_planner.planning.prior_domain import rebuild_domain

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
    scene.add(Box([0.15, 0.15, 0.15]), Pose(domain.end_effector_positions(goal[None])[0].tolist()), name="can")
    return goal, scene


def test_a_blocked_goal_state_is_named_with_what_blocks_it(shipped: tuple[WorldPrior, Any]) -> None:
    prior, domain = shipped
    goal, scene = _goal_in_a_can(prior, domain)
    result = Planner(prior, growth=None, snap_tolerance=1e-6).plan(0, goal, domain.scene_checker(scene))
    assert result.status is PlanStatus.NO_PATH
    reason = result.reason
    assert "from the start (vertex 0: [0.5, 0.7, 0.0, -1.6, 0.0, 2.4, 0.785])" in reason
    assert "to the goal [-0.45, 0.75, 0.0, -1.6, 0.0, 2.4, 0.785]" in reason  # an off-graph state: no vertex id
    assert "all 4 edges joining the goal" in reason
    assert "were checked blocked" in reason
    assert "the goal state itself is blocked: scene object 'can' (panda_" in reason
    assert result.cause is PlanCause.GOAL_BLOCKED
    # With growth, growth checks the goal's state first and stops: no path can exist.
    grown = Planner(prior, snap_tolerance=1e-6).plan(0, goal, domain.scene_checker(scene))
    assert grown.status is PlanStatus.NO_PATH
    assert "can exist" in grown.reason
    assert grown.cause is PlanCause.GOAL_BLOCKED
    assert "goal state itself is blocked (checked): scene object 'can'" in grown.reason


def test_a_walled_in_start_names_the_obstacles_of_its_motions(shipped: tuple[WorldPrior, Any]) -> None:
    prior, domain = shipped
    checker = domain.checker(domain.make_world("table_clutter", 3))
    result = Planner(prior, growth=None).plan(0, 1, checker)
    assert result.status is PlanStatus.NO_PATH
    assert "edges joining the start (vertex 0:" in result.reason
    assert result.cause is PlanCause.START_BLOCKED
    assert re.search(
        r"the start state itself is free, the (8 shortest )?motions are blocked by scene object",
        result.reason,
    )


def test_without_an_explainer_the_reason_still_names_the_states() -> None:
    states = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    graph = ExplicitGraph(np.array([[0, 1], [1, 2]]), np.ones(2), 3, vertex_states=states)
    query = QueryGraph(graph, None, np.ones(2), 0, 2)
    log = [CheckRecord(0, 1, False, "graph", 0.0, 0.0)]
    oracle = TableOracle(np.array([True, False]))
    reason = no_path_reason(query, log, oracle, edge_states_of(_prior_of(graph), query, None))
    assert reason.startswith("no free path from the start (vertex 0: [0.0, 0.0]) to the goal (vertex 2: [2.0, 0.0])")
    assert "1 blocked edges disconnect them (1 checks)" in reason
    assert blocked_end(query, log) is PlanCause.GOAL_BLOCKED  # its only edge is the blocked one
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


class _CountingExplainer:
    """A real helicopter checker whose explanations are counted."""

    def __init__(self, inner: Any) -> None:
        self.inner, self.explained = inner, 0

    def check(self, edge: int) -> bool:
        raise AssertionError("a reason never checks an edge")

    def check_motion(self, states: np.ndarray) -> bool:
        return bool(self.inner.check_motion(states))

    def explain_motion(self, states: np.ndarray) -> str:
        self.explained += 1
        return str(self.inner.explain_motion(states))


def test_an_endpoint_joined_by_many_blocked_motions_explains_only_the_shortest() -> None:
    """A start joined by 40 motions, all blocked by one wall: 8 explanations, not 40 (join growth makes thousands)."""
    from drd_planner.domains.base import domain_from_spec

    ends = [[60.0, 10.0 * i, 50.0, 0.0] for i in range(40)]
    states = np.array([[0.0, 0.0, 50.0, 0.0], *ends, [120.0, 0.0, 50.0, 0.0]])
    edges = np.array([[0, i] for i in range(1, 41)] + [[1, 41]])
    lengths = np.linalg.norm(states[edges[:, 1], :3] - states[edges[:, 0], :3], axis=1)
    graph = ExplicitGraph(edges, lengths, 42, directed=True, vertex_states=states)
    query = QueryGraph(graph, None, np.ones(graph.num_edges), 0, 41)
    scene = Scene(margin=0.0)
    scene.add(Box([2.0, 2000.0, 400.0]), Pose([30.0, 0.0, 50.0]), name="wall")
    explainer = _CountingExplainer(domain_from_spec("helicopter").scene_checker(scene))
    log = [CheckRecord(e + 1, e, False, "graph", 0.0, 0.0) for e in range(40)]  # every join checked blocked
    along = edge_states_of(_prior_of(graph), query, lambda a, b: np.linspace(a, b, 30))
    reason = no_path_reason(query, log, explainer, along)  # type: ignore[arg-type]
    assert "all 40 edges joining the start" in reason
    assert "the start state itself is free, the 8 shortest motions are blocked by" in reason
    assert "'wall'" in reason
    assert explainer.explained == 1 + 8  # the state itself, then the 8 shortest motions


def test_the_blocked_end_is_the_start_when_both_ends_are_walled_in() -> None:
    states = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]])
    graph = ExplicitGraph(np.array([[0, 1], [1, 2], [2, 3]]), np.ones(3), 4, vertex_states=states)
    query = QueryGraph(graph, None, np.ones(3), 0, 3)

    def log(*blocked: int) -> list[CheckRecord]:
        return [CheckRecord(i, e, False, "graph", 0.0, 0.0) for i, e in enumerate(blocked)]

    assert blocked_end(query, log(2)) is PlanCause.GOAL_BLOCKED
    assert blocked_end(query, log(0)) is PlanCause.START_BLOCKED
    assert blocked_end(query, log(2, 0)) is PlanCause.START_BLOCKED  # Nav2 lists the start's code first
    assert blocked_end(query, log(1)) is None
