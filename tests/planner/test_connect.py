"""Off-graph starts and goals: new motions to nearby vertices, their imputed prior, checks of the motions."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner import Planner, PlanStatus, TableOracle, prior_from_problem
from drd_planner.core.problem import Problem
from drd_planner.core.world_columns import WorldColumns
from drd_planner.data.planar_problem import make_planar_problem, planar_problem_worlds
from drd_planner.domains.planar import PlanarChecker
from drd_planner.exceptions import ProblemError
from drd_planner.planner import WorldPrior
from drd_planner.planner.connect import (
    EdgeSampleIndex,
    MotionOracle,
    connector_for,
    imputed_columns,
    imputed_outcomes,
    imputed_shares,
)
from drd_planner.planner.straight_connector import StraightConnector


class PlanarWorldOracle:
    """Graph edges from X, motions against the world's boxes (the exact planar checker)."""

    def __init__(self, row: np.ndarray, checker: PlanarChecker) -> None:
        self._table = TableOracle(row)
        self._checker = checker
        self.motions_checked = 0

    def check(self, edge: int) -> bool:
        return self._table.check(edge)

    def check_motion(self, states: np.ndarray) -> bool:
        self.motions_checked += 1
        return self._checker.check_motion(states)


@pytest.fixture(scope="module")
def planar() -> tuple[Problem, list[np.ndarray], WorldPrior]:
    problem = make_planar_problem(model="forest", num_worlds=300, seed=5)
    boxes = planar_problem_worlds(problem)
    return problem, boxes, prior_from_problem(problem, domain="planar")


def _off_graph_state(prior: WorldPrior, rng: np.random.Generator, planner: Planner) -> np.ndarray:
    states = prior.graph.vertex_states
    assert states is not None
    while True:
        e = int(rng.integers(prior.graph.num_edges))
        a, b = states[prior.graph.edges[e]]
        point = a + rng.uniform(0.3, 0.7) * (b - a)
        if np.min(np.linalg.norm(states - point, axis=1)) > planner.snap_tolerance:
            return point


def test_an_off_graph_start_is_joined_checked_and_verified(
    planar: tuple[Problem, list[np.ndarray], WorldPrior],
) -> None:
    problem, boxes, prior = planar
    planner = Planner(prior)
    assert isinstance(planner.connector, StraightConnector)
    rng = np.random.default_rng(0)
    worlds = problem.require_worlds()
    found = 0
    for k in range(12):
        world = int(worlds.test_ids[k])
        checker = PlanarChecker(prior.graph, boxes[world])
        oracle = PlanarWorldOracle(worlds.X[world], checker)
        assert isinstance(oracle, MotionOracle)
        start = _off_graph_state(prior, rng, planner)
        result = planner.plan(start, problem.goal, oracle, seed=k)  # type: ignore[arg-type]
        assert result.status in (PlanStatus.FOUND, PlanStatus.NO_PATH)
        if not result.found:
            continue
        found += 1
        v = prior.graph.num_vertices
        assert result.vertices[0] == v
        assert np.allclose(result.new_states[v], start)
        first = int(result.edges[0])
        assert first >= prior.graph.num_edges
        assert first in result.motions
        assert checker.check_motion(result.motions[first])  # the motion really is free in this world
        assert oracle.motions_checked >= 1
        assert all(result.outcomes()[int(e)] for e in result.edges)
        for e in result.edges.tolist():  # the rest of the path is free in the world too
            if e < prior.graph.num_edges:
                assert worlds.X[world, e]
    assert found >= 6


def test_an_off_graph_goal_and_the_cache(planar: tuple[Problem, list[np.ndarray], WorldPrior]) -> None:
    problem, boxes, prior = planar
    planner = Planner(prior)
    world = int(problem.require_worlds().test_ids[0])
    oracle = PlanarWorldOracle(problem.require_worlds().X[world], PlanarChecker(prior.graph, boxes[world]))
    goal = _off_graph_state(prior, np.random.default_rng(3), planner)
    first = planner.plan(problem.start, goal, oracle)  # type: ignore[arg-type]
    again = planner.plan(problem.start, goal, oracle)  # type: ignore[arg-type]
    assert first.query == again.query == "connected"
    assert [c.edge for c in first.checks] == [c.edge for c in again.checks]
    assert len(planner.cached_queries()) == 1
    if first.found:
        assert first.vertices[-1] == prior.graph.num_vertices


def test_refusals_for_unreachable_states_and_plain_oracles(
    planar: tuple[Problem, list[np.ndarray], WorldPrior],
) -> None:
    problem, boxes, prior = planar
    planner = Planner(prior)
    row = problem.require_worlds().X[0]
    far = planner.plan([5.0, 5.0], problem.goal, PlanarWorldOracle(row, PlanarChecker(prior.graph, boxes[0])))  # type: ignore[arg-type]
    assert far.status is PlanStatus.REFUSED
    assert "reach" in far.reason
    near = _off_graph_state(prior, np.random.default_rng(1), planner)
    plain = planner.plan(near, problem.goal, TableOracle(row))  # type: ignore[arg-type]
    assert plain.status is PlanStatus.REFUSED
    assert "check_motion" in plain.reason
    off = Planner(prior, connect_states=False).plan(near, problem.goal, TableOracle(row))  # type: ignore[arg-type]
    assert off.status is PlanStatus.REFUSED
    assert "connector" in off.reason


@pytest.mark.slow
def test_imputed_free_probability_tracks_the_true_one(
    planar: tuple[Problem, list[np.ndarray], WorldPrior],
) -> None:
    # Motions from random off-graph states: the imputed fraction of free training worlds against the
    # fraction of the same worlds in which the motion really is free (exact box test).
    problem, boxes, prior = planar
    planner = Planner(prior)
    connector = planner.connector
    assert connector is not None
    assert prior.worlds is not None
    index = EdgeSampleIndex(prior.graph, None, position_dims=connector.position_dims)
    train = problem.require_worlds().train_ids
    rng = np.random.default_rng(7)
    imputed, truth = [], []
    for _ in range(40):
        state = _off_graph_state(prior, rng, planner)
        for motion in connector.connect(state, prior.graph, outgoing=True):
            imputed.append(imputed_outcomes(index, prior.worlds, motion.states).mean())
            truth.append(np.mean([PlanarChecker(prior.graph, boxes[h]).check_motion(motion.states) for h in train]))
    imputed_a, truth_a = np.array(imputed), np.array(truth)
    marginal = float(prior.worlds.mean())
    assert np.corrcoef(imputed_a, truth_a)[0, 1] > 0.6
    assert np.abs(imputed_a - truth_a).mean() < np.abs(marginal - truth_a).mean()


def test_the_connector_registry_by_domain(planar: tuple[Problem, list[np.ndarray], WorldPrior]) -> None:
    _, _, prior = planar
    assert isinstance(connector_for(prior), StraightConnector)
    unknown = WorldPrior(**{**prior.__dict__, "domain": "se2"})
    assert connector_for(unknown) is None


def test_the_explanation_protocol_is_optional_and_the_arm_checker_has_it(small_arm: object) -> None:
    from drd_planner.geometry.scene import Scene
    from drd_planner.planner.connect import MotionExplainer

    checker = small_arm.scene_checker(Scene(margin=0.0))  # type: ignore[attr-defined]
    assert isinstance(checker, MotionExplainer)
    assert isinstance(checker, MotionOracle)
    assert not isinstance(TableOracle(np.ones(3, dtype=bool)), MotionExplainer)


def test_imputed_columns_are_the_majority_vote_of_the_motions_samples() -> None:
    from drd_planner.core.graph import ExplicitGraph

    states = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    graph = ExplicitGraph(np.array([[0, 1], [1, 2], [2, 3], [3, 0]]), np.ones(4), 4, vertex_states=states)
    worlds = np.array([[True, False, True, True], [True, True, False, False], [False, True, True, True]])
    index = EdgeSampleIndex(graph, None, position_dims=2)
    motions = [
        np.linspace([0.1, 0.0], [0.9, 0.0], 5),
        np.linspace([1.0, 0.2], [1.0, 0.8], 3),
        np.array([[0.5, 1.0]]),
    ]
    columns = imputed_columns(index, worlds, motions)
    expected = np.column_stack([imputed_outcomes(index, worlds, m) for m in motions])  # <= 8 samples: the same
    np.testing.assert_array_equal(columns, expected)
    np.testing.assert_array_equal(imputed_columns(index, WorldColumns(worlds), motions), expected)  # packed
    assert imputed_columns(index, worlds, []).shape == (3, 0)
    assert imputed_columns(index, WorldColumns(worlds), []).shape == (3, 0)
    long = np.linspace([0.0, 0.1], [0.0, 0.9], 50)  # 50 samples voted through 8 evenly spread ones
    assert imputed_columns(index, worlds, [long]).shape == (3, 1)


def test_imputed_shares_are_the_imputed_columns_averaged() -> None:
    from drd_planner.core.graph import ExplicitGraph

    rng = np.random.default_rng(3)
    side = 6
    xy = np.stack(np.meshgrid(np.arange(side), np.arange(side)), axis=-1).reshape(-1, 2).astype(float)
    ids = np.arange(side * side).reshape(side, side)
    pairs = np.concatenate(
        [
            np.column_stack([ids[:, :-1].ravel(), ids[:, 1:].ravel()]),
            np.column_stack([ids[:-1].ravel(), ids[1:].ravel()]),
        ]
    )
    graph = ExplicitGraph(pairs, np.ones(len(pairs)), side * side, vertex_states=xy)
    worlds = rng.random((97, len(pairs))) < 0.55
    index = EdgeSampleIndex(graph, None, position_dims=2)
    columns = WorldColumns(worlds)
    for k in (1, 3, 8, 20):
        ends = rng.uniform(0, side - 1, (40, 2, 2))
        points = np.linspace(ends[:, 0], ends[:, 1], k, axis=1)  # (40, k, 2)
        expected = np.average(imputed_columns(index, worlds, list(points)), axis=0)
        np.testing.assert_array_equal(imputed_shares(index, columns, points), expected)
        weights = rng.uniform(0.1, 2.0, 97)
        weighted = np.average(imputed_columns(index, worlds, list(points)), axis=0, weights=weights)
        np.testing.assert_array_equal(imputed_shares(index, columns, points, weights), weighted)
    assert imputed_shares(index, columns, np.zeros((0, 4, 2))).shape == (0,)
    with pytest.raises(ProblemError, match="M, K, D"):
        imputed_shares(index, columns, np.zeros((4, 2)))
