"""The probe: a new query's union path checked before its library is built, and the library after a blocked edge."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner import Planner, PlanStage, PlanStatus, TableOracle
from drd_planner.core.episode import GraphPathPolicy
from drd_planner.core.lazysp import GraphArcs
from drd_planner.core.problem import Problem
from drd_planner.core.status import PlanCause
from drd_planner.core.world_columns import WorldColumns
from drd_planner.data.planar_problem import planar_problem_worlds
from drd_planner.domains.planar import PlanarChecker
from drd_planner.exceptions import ProblemError
from drd_planner.planner import WorldPrior
from drd_planner.planner.goal_trees import SearchWorlds
from drd_planner.planner.probe import (
    DEFAULT_PROBE_PROBABILITY,
    Probe,
    ProbePolicy,
    check_probe_probability,
    union_probe,
)
from drd_planner.planner.query_graph import prior_query
from drd_planner.planner.query_library import ShortestPaths


@pytest.fixture(scope="module")
def problem(forest_problem: Problem) -> Problem:
    return forest_problem


@pytest.fixture(scope="module")
def prior(forest_prior: WorldPrior) -> WorldPrior:
    return forest_prior


def _queries(prior: WorldPrior, count: int, seed: int) -> list[tuple[int, int]]:
    rng = np.random.default_rng(seed)
    n = prior.graph.num_vertices
    out: list[tuple[int, int]] = []
    while len(out) < count:
        s, g = (int(v) for v in rng.integers(n, size=2))
        if s != g:
            out.append((s, g))
    return out


def _probed(planner: Planner, prior: WorldPrior, count: int) -> list[tuple[int, int, Probe]]:
    """Queries of the prior that get a probe at the planner's threshold."""
    out = []
    for s, g in _queries(prior, 200, seed=5):
        model = planner.query_model(s, g)
        if model.probe is not None:
            out.append((s, g, model.probe))
        if len(out) == count:
            break
    assert len(out) == count, "the fixture has too few probed queries"
    return out


def test_the_probe_is_the_union_shortest_path_with_its_training_probability(prior: WorldPrior) -> None:
    assert prior.worlds is not None
    search = SearchWorlds(GraphArcs(prior.graph), prior.graph.lengths, prior.worlds, seed=prior.library_seed)
    anywhere = prior.worlds[search.worlds].any(axis=0)
    columns = WorldColumns(prior.worlds)
    shortest = ShortestPaths(GraphArcs(prior.graph), prior.graph.lengths)
    seen = 0
    for s, g in _queries(prior, 30, seed=2):
        query = prior_query(prior, s, g, columns)
        probe = union_probe(search, query, None, probability=0.0)
        union = shortest.path(s, g, anywhere)
        if union is None:
            assert probe is None
            continue
        assert probe is not None
        seen += 1
        lengths = prior.graph.lengths
        assert float(lengths[probe.edges].sum()) == pytest.approx(float(lengths[union].sum()))
        assert anywhere[probe.edges].all()
        expected = float(prior.worlds[:, probe.edges].all(axis=1).mean())
        assert probe.free_probability == pytest.approx(expected)
        assert sorted(probe.order.tolist()) == sorted(probe.edges.tolist())
        share = prior.worlds[:, probe.order].mean(axis=0)
        assert np.all(np.diff(share) >= 0), "least often free first"
        higher = union_probe(search, query, None, probability=min(1.0, expected + 1e-9))
        assert (higher is None) == (expected + 1e-9 <= 1.0)
    assert seen > 10


def test_weights_weigh_the_probability(prior: WorldPrior) -> None:
    assert prior.worlds is not None
    search = SearchWorlds(GraphArcs(prior.graph), prior.graph.lengths, prior.worlds, seed=prior.library_seed)
    s, g = next((s, g) for s, g in _queries(prior, 50, seed=3) if search.union_walk(g, s)[0].size > 1)
    query = prior_query(prior, s, g, WorldColumns(prior.worlds))
    plain = union_probe(search, query, None, probability=0.0)
    assert plain is not None
    free = prior.worlds[:, plain.edges].all(axis=1)
    weights = np.where(free, 3.0, 1.0)
    weighted = union_probe(search, query, weights, probability=0.0)
    assert weighted is not None
    assert weighted.free_probability == pytest.approx(float(np.average(free, weights=weights)))
    if 0 < free.mean() < 1:
        assert weighted.free_probability > plain.free_probability


def test_the_probe_policy_asks_in_order_and_stops_at_a_blocked_edge() -> None:
    probe = Probe(np.array([4, 7, 9]), 0.8, np.array([9, 4, 7]))
    policy = ProbePolicy(probe)
    assert (policy.name, policy.stage) == ("probe", "probe")
    assert isinstance(policy, GraphPathPolicy)
    assert (policy.stops_on_library_path, policy.max_checks) == (False, None)
    assert policy.select() == 9
    policy.observe(9, True)
    assert policy.proposed_path() is probe.edges
    assert policy.select() == 4
    policy.observe(4, False)
    assert policy.select() is None
    assert policy.proposed_path() is None
    done = ProbePolicy(probe)
    for edge in (9, 4, 7):
        assert done.select() == edge
        done.observe(edge, True)
    assert done.select() is None


def test_a_free_probe_is_the_plan_its_edges_the_only_checks_and_no_library_is_built(
    problem: Problem, prior: WorldPrior
) -> None:
    planner = Planner(prior)
    worlds = problem.require_worlds()
    found = 0
    for i, (s, g, probe) in enumerate(_probed(planner, prior, 12)):
        row = worlds.X[int(worlds.test_ids[i % worlds.test_ids.size])]
        if not row[probe.edges].all():
            continue
        found += 1
        result = planner.plan(s, g, TableOracle(row))
        assert result.status is PlanStatus.FOUND
        assert result.stage is PlanStage.PROBE
        assert [c.edge for c in result.checks] == probe.order.tolist()
        assert {c.stage for c in result.checks} == {"probe"}
        assert result.edges.tolist() == probe.edges.tolist()
        assert result.vertices[0] == s
        assert result.vertices[-1] == g
        assert planner.query_model(s, g).library is None  # never needed
    assert found >= 3


def test_a_blocked_probe_hands_its_outcomes_to_the_library_and_nothing_is_checked_twice(
    problem: Problem, prior: WorldPrior
) -> None:
    planner = Planner(prior)
    plain = Planner(prior, probe_probability=None)
    worlds = problem.require_worlds()
    blocked = 0
    for s, g, probe in _probed(planner, prior, 40):
        for world in worlds.test_ids.tolist():
            row = worlds.X[int(world)]
            if row[probe.edges].all():
                continue
            blocked += 1
            result = planner.plan(s, g, TableOracle(row))
            edges = [c.edge for c in result.checks]
            assert len(set(edges)) == len(edges)
            first_blocked = next(i for i, e in enumerate(probe.order.tolist()) if not row[e])
            assert edges[: first_blocked + 1] == probe.order[: first_blocked + 1].tolist()
            assert [c.stage for c in result.checks[: first_blocked + 1]] == ["probe"] * (first_blocked + 1)
            assert all(c.stage != "probe" for c in result.checks[first_blocked + 1 :])
            assert [c.step for c in result.checks] == list(range(len(edges)))
            other = plain.plan(s, g, TableOracle(row))
            assert result.status is other.status
            if result.found:
                assert row[result.edges].all()
                assert all(result.outcomes()[int(e)] for e in result.edges)
            built = planner.query_model(s, g)
            assert built.library is not None  # built for the library stage
            assert result.timings.library_s >= built.build_s  # and its time counted as the library's
            break
        if blocked >= 4:
            break
    assert blocked >= 4


def test_budgets_stop_the_probe(problem: Problem, prior: WorldPrior) -> None:
    planner = Planner(prior)
    worlds = problem.require_worlds()
    s, g, probe = next(q for q in _probed(planner, prior, 40) if q[2].edges.size >= 2)
    row = np.ones_like(worlds.X[0])
    result = planner.plan(s, g, TableOracle(row), max_checks=1)
    assert result.status is PlanStatus.BUDGET_EXHAUSTED
    assert result.cause is PlanCause.CHECK_BUDGET
    assert result.num_checks == 1
    assert (result.checks[0].edge, result.checks[0].stage) == (int(probe.order[0]), "probe")


def test_other_policies_and_no_threshold_make_no_probe(problem: Problem, prior: WorldPrior) -> None:
    planner = Planner(prior)
    worlds = problem.require_worlds()
    s, g, _ = _probed(planner, prior, 1)[0]
    row = worlds.X[int(worlds.test_ids[0])]
    for policy in ("bisect", "max_tally"):
        result = planner.plan(s, g, TableOracle(row), policy=policy)
        assert all(c.stage != "probe" for c in result.checks)
    off = Planner(prior, probe_probability=None)
    assert off.query_model(s, g).probe is None
    assert all(c.stage != "probe" for c in off.plan(s, g, TableOracle(row)).checks)
    assert DEFAULT_PROBE_PROBABILITY == 0.5


def test_an_online_tree_goes_on_from_a_blocked_probe(problem: Problem, prior: WorldPrior) -> None:
    """A query whose tree is grown online probes too; after a blocked edge the tree walks on the outcomes."""
    planner = Planner(prior)
    planner.set_leaf(0.05, None)
    plain = Planner(prior, probe_probability=None)
    plain.set_leaf(0.05, None)
    worlds = problem.require_worlds()
    free = tree_checks = 0
    for s, g, probe in _probed(planner, prior, 40):
        row = worlds.X[int(worlds.test_ids[(s + g) % worlds.test_ids.size])]
        result = planner.plan(s, g, TableOracle(row))
        edges = [c.edge for c in result.checks]
        assert len(set(edges)) == len(edges)  # nothing checked twice
        assert result.status is plain.plan(s, g, TableOracle(row)).status
        if row[probe.edges].all():
            free += 1
            assert result.stage is PlanStage.PROBE
            assert edges == probe.order.tolist()
            continue
        first_blocked = next(i for i, e in enumerate(probe.order.tolist()) if not row[e])
        assert edges[: first_blocked + 1] == probe.order[: first_blocked + 1].tolist()
        tree_checks += sum(c.stage == "tree" for c in result.checks)
        assert planner.query_model(s, g).tree is not None
    assert free >= 3
    assert tree_checks >= 3  # the tree asked edges after the probe


@pytest.mark.parametrize("bad", [-0.1, 1.5, float("nan")])
def test_a_probability_outside_0_1_is_refused(prior: WorldPrior, bad: float) -> None:
    with pytest.raises(ProblemError, match="probe_probability must lie in"):
        check_probe_probability(bad)
    with pytest.raises(ProblemError, match="probe_probability must lie in"):
        Planner(prior, probe_probability=bad)


class _MotionTable(TableOracle):
    """Graph edges from a row of X, joined motions against the world's boxes."""

    def __init__(self, row: np.ndarray, checker: PlanarChecker) -> None:
        super().__init__(row)
        self.checker = checker

    def check_motion(self, states: np.ndarray) -> bool:
        return self.checker.check_motion(states)


def _between(prior: WorldPrior, rng: np.random.Generator, tolerance: float) -> np.ndarray:
    """A state midway along a random edge, farther than ``tolerance`` from every vertex."""
    states = prior.graph.vertex_states
    assert states is not None
    while True:
        a, b = states[prior.graph.edges[int(rng.integers(prior.graph.num_edges))]]
        point = a + rng.uniform(0.3, 0.7) * (b - a)
        if np.min(np.linalg.norm(states - point, axis=1)) > tolerance:
            return point


def test_off_graph_queries_probe_through_their_motions(problem: Problem, prior: WorldPrior) -> None:
    boxes = planar_problem_worlds(problem)
    planner = Planner(prior)
    worlds = problem.require_worlds()
    rng = np.random.default_rng(4)
    big_e = prior.graph.num_edges
    kinds: dict[str, int] = {}
    for k in range(60):
        start = _between(prior, rng, planner.snap_tolerance)
        goal = _between(prior, rng, planner.snap_tolerance) if k % 2 else int(rng.integers(prior.graph.num_vertices))
        model = planner.query_model(start, goal)
        if model.probe is None:
            continue
        assert model.probe.edges[0] >= big_e  # the start's motion first
        if k % 2:
            assert model.probe.edges[-1] >= big_e  # and the goal's last
        world = int(worlds.test_ids[k % worlds.test_ids.size])
        oracle = _MotionTable(worlds.X[world], PlanarChecker(prior.graph, boxes[world]))
        result = planner.plan(start, goal, oracle)
        if result.stage is PlanStage.PROBE:
            assert result.edges.tolist() == model.probe.edges.tolist()
            assert [c.edge for c in result.checks] == model.probe.order.tolist()
            for e in result.edges.tolist():
                if e >= big_e:
                    assert oracle.checker.check_motion(result.motions[e])
                else:
                    assert worlds.X[world, e]
            kinds["probe"] = kinds.get("probe", 0) + 1
        elif result.found:
            assert all(result.outcomes()[int(e)] for e in result.edges)
            assert any(c.stage == "probe" and not c.free for c in result.checks)
            kinds["after"] = kinds.get("after", 0) + 1
    assert kinds.get("probe", 0) >= 3
