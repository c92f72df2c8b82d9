"""More joins for an off-graph helicopter state when its first ones are all blocked (issue 29)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import SHARED_DATA

from drd_planner.planner import load_prior
from drd_planner.planner.connect import POINTS_PER_EDGE, imputed_columns
from drd_planner.planner.dubins_connector import DubinsConnector
from drd_planner.planner.join_growth import SketchedJoins, more_joins_of, still_open
from drd_planner.planner.join_ranking import PriorRanking
from drd_planner.planner.planner import Planner
from drd_planner.planner.prior import WorldPrior
from drd_planner.planner.result import PlanStage, PlanStatus
from drd_planner.planner.roadmap_growth import GrowthSettings
from drd_planner.planning.prior_domain import rebuild_domain

PRIOR = Path(__file__).resolve().parents[2] / "trees" / "heli_wires.npz"
LINES = PRIOR.with_name("heli_lines.npz")
START = np.array([212.0, 33.0, 60.0, 2.9])  # flying west in an east-going lattice: its joins must turn


class JoinWall:
    """Every lattice edge free; a motion is blocked when it joins one of the ``blocked`` vertices (either end)."""

    def __init__(self, prior: WorldPrior, blocked: set[int]) -> None:
        self.states = prior.graph.vertex_states
        self.blocked = blocked
        self.motions = 0

    def check(self, edge: int) -> bool:
        return True

    def check_motion(self, states: np.ndarray) -> bool:
        self.motions += 1
        if states.shape[0] == 1:  # the state itself
            return True
        assert self.states is not None
        tail = np.all(np.isclose(self.states[:, :3], states[0, :3]), axis=1)
        head = np.all(np.isclose(self.states[:, :3], states[-1, :3]), axis=1)
        return not any(int(v) in self.blocked for v in np.flatnonzero(tail | head))


@pytest.fixture(scope="module")
def prior() -> WorldPrior:
    return load_prior(PRIOR)


def _first_joins(planner: Planner, count: int) -> set[int]:
    connector = planner.connector
    assert isinstance(connector, DubinsConnector)
    return set(connector.ranked(START, planner.prior.graph, outgoing=True)[:count].tolist())


def test_blocked_first_joins_grow_to_a_free_one(prior: WorldPrior) -> None:
    planner = Planner(prior, snap_tolerance=1e-6)
    assert more_joins_of(planner.connector) is not None
    goal = int(prior.trees[0].goal)
    wall = JoinWall(prior, _first_joins(planner, 40) | {goal})  # more than the first 16, and the one to the goal
    result = planner.plan(START, goal, wall)
    # 16 joins and the one straight to the goal, then 64 more by the prior
    assert result.status is PlanStatus.FOUND
    assert result.stage is PlanStage.GROW
    assert result.growth is not None
    assert result.growth.rounds == 1
    first = int(result.edges[0])
    assert first in result.motions
    assert np.allclose(result.motions[first][0], START)
    assert wall.check_motion(result.motions[first])  # the join it flies is a free one
    again = Planner(prior, snap_tolerance=1e-6).plan(START, int(prior.trees[0].goal), JoinWall(prior, wall.blocked))
    assert [(c.edge, c.free) for c in again.checks] == [(c.edge, c.free) for c in result.checks]
    without = Planner(prior, snap_tolerance=1e-6, growth=None).plan(START, int(prior.trees[0].goal), wall)
    assert without.status is PlanStatus.NO_PATH


def test_when_every_join_is_blocked_the_reason_says_what_was_tried(prior: WorldPrior) -> None:
    planner = Planner(prior, snap_tolerance=1e-6, growth=GrowthSettings(max_joins=64))
    wall = JoinWall(prior, _first_joins(planner, 10**6))
    result = planner.plan(START, int(prior.trees[0].goal), wall)
    # max_joins 64
    assert result.status is PlanStatus.NO_PATH
    assert result.growth is not None
    assert result.growth.stop == "exhausted"
    assert result.growth.edges_added == 64 - 17  # beside the 16 nearest joins, the one straight to the goal
    assert "blocked" in result.reason
    assert "64" in result.reason


def test_joins_go_only_where_the_other_end_can_still_be_reached(prior: WorldPrior) -> None:
    planner = Planner(prior, snap_tolerance=1e-6)
    goal = int(prior.trees[0].goal)
    into_goal = set(np.flatnonzero(prior.graph.edges[:, 1] == goal).tolist())

    class GoalCutOff(JoinWall):
        def check(self, edge: int) -> bool:
            return edge not in into_goal  # the goal cannot be reached by any lattice edge

    wall = GoalCutOff(prior, _first_joins(planner, 16) | {goal})  # no motion joins the goal either
    result = planner.plan(START, goal, wall)
    assert result.status is PlanStatus.NO_PATH
    assert result.growth is not None
    # Joins go only to vertices that may still reach the goal; as the edges into the goal turn out blocked there
    # are none left after the first round's 64 and a few more (not the 496 a join to every vertex would make).
    assert result.growth.stop == "exhausted"
    assert result.growth.edges_added <= 80
    known = result.outcomes()
    assert all(known[e] is False for e in into_goal if e in known)


def test_still_open_follows_direction_and_skips_blocked_edges() -> None:
    edges = np.array([[0, 1], [1, 2], [2, 3], [3, 1]])
    open_edges = np.array([True, True, False, True])
    forward = still_open(edges, 5, open_edges, 0, directed=True, reverse=False)
    assert forward.tolist() == [True, True, True, False, False]
    backward = still_open(edges, 5, open_edges, 1, directed=True, reverse=True)
    assert backward.tolist() == [True, True, False, True, False]
    both = still_open(edges, 5, open_edges, 2, directed=False, reverse=False)
    assert both.tolist() == [True, True, True, True, False]


def test_a_goal_without_heading_grows_its_joins_too(prior: WorldPrior) -> None:
    planner = Planner(prior, snap_tolerance=1e-6)
    goal = np.array([478.0, -33.0, 70.0])  # x, y, z: any arrival heading
    connector = planner.connector
    assert isinstance(connector, DubinsConnector)
    first = set(connector.ranked(np.append(goal, np.nan), prior.graph, outgoing=False)[:20].tolist())
    result = planner.plan(0, goal, JoinWall(prior, first | {0}))  # nor the motion straight from the start
    assert result.status is PlanStatus.FOUND
    assert result.stage is PlanStage.GROW
    last = result.motions[int(result.edges[-1])]
    assert np.allclose(last[-1, :3], goal)
    assert np.isfinite(last).all()


def test_the_ranking_follows_the_lazy_weight_of_each_sketched_join(prior: WorldPrior) -> None:
    planner = Planner(prior, snap_tolerance=1e-6)
    connector = planner.connector
    assert isinstance(connector, SketchedJoins)
    assert isinstance(connector, DubinsConnector)
    ranking = connector.ranked(START, prior.graph, outgoing=True)
    lengths, points = connector.sketches(
        START, prior.graph, ranking, outgoing=True, fractions=np.linspace(0, 1, POINTS_PER_EDGE)
    )
    index = planner._models.sample_index()
    ordered = PriorRanking.of_prior(ranking, lengths, points, index, prior).first(ranking.size)
    assert sorted(ordered.tolist()) == sorted(ranking.tolist())
    assert not np.array_equal(ordered, ranking)
    theta = np.average(imputed_columns(index, prior.worlds, list(points)), axis=0, weights=prior.world_weights)
    weight = -np.log(np.clip(theta, 1e-3, 1.0)) + 0.0 * lengths
    position = {int(v): i for i, v in enumerate(ranking.tolist())}
    surprise = weight[[position[int(v)] for v in ordered.tolist()]]
    assert surprise[:16].mean() <= surprise[-16:].mean()  # likely-free joins first


# Two states of ``scripts/experiments/bench_heli_states.py --priors heli_lines --states 12 --free-states --seed 1`` that
# ran out of the 10 s growth budget when joins were offered by length (1071 and 2100 checks): a start low in a
# valley (10 m off a vertex; every one of its 600 shortest joins is blocked) and a goal 2 m off a vertex whose
# short joins lead into a part of the lattice the start cannot reach. The corridors world of each is the seed.
HARD_STATES = [
    (
        np.array([499.89537571569093, -740.0005473270216, 33.29849282555711, -0.40066668029136476]),
        True,
        1010004,
    ),
    (
        np.array([1248.0001469909878, -1250.0242475224525, 47.1124999869474, -2.548780246100255]),
        False,
        1002011,
    ),
]


@pytest.mark.parametrize(("state", "is_start", "world"), HARD_STATES)
def test_hard_states_of_the_real_scale_prior_plan_within_a_few_hundred_checks(
    state: np.ndarray, is_start: bool, world: int
) -> None:
    if not (SHARED_DATA / "terrain" / "srtm_front_range_144.asc").is_file():
        pytest.skip("the shared elevation model is needed to draw the heli_lines world")
    lines = load_prior(LINES)
    domain = rebuild_domain(lines, "heli_lines")
    checker = domain.checker(domain.make_world("corridors", world))
    planner = Planner(lines, snap_tolerance=1e-6, growth=GrowthSettings(seconds=None, max_checks=200))
    start, goal = (state, int(domain.goal)) if is_start else (int(domain.start), state)
    result = planner.plan(start, goal, checker)
    assert result.status is PlanStatus.FOUND, result.reason
    assert result.stage is PlanStage.GROW, result.reason
    assert result.num_checks <= 250
    known = result.outcomes()
    assert all(known.get(int(e)) is True for e in result.edges)  # every edge and joining motion checked free
    joins = [result.motions[int(e)] for e in result.edges if int(e) in result.motions]
    assert joins
    assert all(checker.check_motion(m) for m in joins)


class Pocket(JoinWall):
    """Joins free but the one straight to the goal; every edge out of the ``pocket`` vertices blocked."""

    def __init__(self, prior: WorldPrior, pocket: set[int]) -> None:
        super().__init__(prior, {int(prior.trees[0].goal)})
        self.leaving = {int(e) for e in np.flatnonzero(np.isin(prior.graph.edges[:, 0], sorted(pocket)))}

    def check(self, edge: int) -> bool:
        return edge not in self.leaving


def test_more_joins_begin_before_the_graph_stage_proves_the_first_ones_lead_nowhere(prior: WorldPrior) -> None:
    goal = int(prior.trees[0].goal)
    first = _first_joins(Planner(prior, snap_tolerance=1e-6), 16)
    late = Planner(prior, snap_tolerance=1e-6, growth=GrowthSettings(graph_checks_first=None))
    early = Planner(prior, snap_tolerance=1e-6, growth=GrowthSettings(graph_checks_first=4))
    proved, cut = late.plan(START, goal, Pocket(prior, first)), early.plan(START, goal, Pocket(prior, first))
    for result in (proved, cut):
        assert result.status is PlanStatus.FOUND, result.reason
        assert result.stage is PlanStage.GROW
        known = result.outcomes()
        assert all(known.get(int(e)) is True for e in result.edges)
    assert int(cut.edges[0]) in cut.motions
    assert cut.motions[int(cut.edges[0])][-1, :3].tolist() not in [
        prior.graph.vertex_states[v, :3].tolist() for v in first
    ]
    graph_checks = [c for c in cut.checks if c.stage == "graph"]
    assert len(graph_checks) <= 4 + 1  # the library's last word aside, the graph stage stopped at 4
    assert cut.num_checks < proved.num_checks


def test_a_graph_stage_cut_short_still_proves_no_path_when_growth_finds_none(prior: WorldPrior) -> None:
    goal = int(prior.trees[0].goal)
    first = _first_joins(Planner(prior, snap_tolerance=1e-6), 16)
    results = []
    for checks_first in (None, 4):
        settings = GrowthSettings(max_joins=16, graph_checks_first=checks_first)  # no join beyond the first
        planner = Planner(prior, snap_tolerance=1e-6, growth=settings)
        results.append(planner.plan(START, goal, Pocket(prior, first)))
    proved, cut = results
    assert proved.status is PlanStatus.NO_PATH
    assert cut.status is PlanStatus.NO_PATH
    assert cut.cause == proved.cause
    assert sorted(c.edge for c in cut.checks if not c.free) == sorted(c.edge for c in proved.checks if not c.free)


class OnlyMotions(JoinWall):
    """Every lattice edge blocked; a motion is blocked when it joins a ``blocked`` vertex."""

    def check(self, edge: int) -> bool:
        return False


def test_an_off_graph_end_is_also_joined_straight_to_the_other_end(prior: WorldPrior) -> None:
    planner = Planner(prior, snap_tolerance=1e-6, growth=None)
    goal = int(prior.trees[0].goal)
    query = planner.query_graph(START, goal)
    assert query.start_joins is not None
    nearest = _first_joins(planner, 16)
    assert goal not in nearest
    assert set(query.start_joins.vertices.tolist()) == nearest | {goal}  # once: the 16 nearest and the goal
    result = planner.plan(START, goal, OnlyMotions(prior, set()))  # no lattice edge is free: only that motion
    assert result.status is PlanStatus.FOUND
    assert result.num_checks == 1
    (edge,) = result.edges.tolist()
    motion = result.motions[int(edge)]
    assert np.allclose(motion[0], START)
    assert prior.graph.vertex_states is not None
    assert np.allclose(motion[-1], prior.graph.vertex_states[goal])
    # an off-graph goal from a start vertex: the same, the other way
    start = int(query.start_joins.vertices[0])
    state = prior.graph.vertex_states[goal] + np.array([-30.0, 20.0, 0.0, 0.0])
    back = planner.query_graph(start, state)
    assert back.goal_joins is not None
    assert start in back.goal_joins.vertices.tolist()
    # a vertex no flyable motion reaches (a climb steeper than the gradient) gets no straight join
    steep = START.copy()
    steep[2] = prior.graph.vertex_states[goal, 2] + 5000.0
    connector = planner.connector
    assert isinstance(connector, DubinsConnector)
    assert connector.motions_to(steep, prior.graph, np.array([goal]), outgoing=True) == []
