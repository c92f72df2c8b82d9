"""The Planner: any query of a prior, safe results, complete over the graph, budgets, refusals."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from drd_planner import PLAN_POLICIES, Planner, PlanStage, PlanStatus, TableOracle, prior_from_problem
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.lazysp import GraphArcs
from drd_planner.core.library import PathLibrary
from drd_planner.core.problem import Problem
from drd_planner.core.tree import build_tree
from drd_planner.core.worlds import WorldDatabase
from drd_planner.data.planar_problem import make_planar_problem
from drd_planner.exceptions import ProblemError
from drd_planner.planner import QueryTree, WorldPrior
from drd_planner.planner.query_library import ShortestPaths


@pytest.fixture(scope="module")
def problem() -> Problem:
    return make_planar_problem(model="forest", num_worlds=300, seed=7)


@pytest.fixture(scope="module")
def prior(problem: Problem) -> WorldPrior:
    tree = build_tree(problem, progress=False)
    assert problem.start is not None
    assert problem.goal is not None
    own = QueryTree("own", problem.start, problem.goal, problem.library, tree)
    return prior_from_problem(problem, domain="planar", trees=(own,), eta=0.2)


def _free_path_exists(problem: Problem, world: int, start: int, goal: int) -> bool:
    graph = problem.graph
    assert graph is not None
    search = ShortestPaths(GraphArcs(graph), graph.lengths)
    return search.path(start, goal, problem.require_worlds().X[world]) is not None


def _queries(problem: Problem, count: int, seed: int) -> list[tuple[int, int]]:
    rng = np.random.default_rng(seed)
    n = problem.graph.num_vertices  # type: ignore[union-attr]
    pairs = []
    while len(pairs) < count:
        s, g = (int(v) for v in rng.integers(n, size=2))
        if s != g:
            pairs.append((s, g))
    return pairs


@pytest.mark.slow
def test_every_found_path_was_checked_free_and_no_path_is_exact(problem: Problem, prior: WorldPrior) -> None:
    planner = Planner(prior)
    worlds = problem.require_worlds()
    statuses = set()
    for i, (s, g) in enumerate(_queries(problem, 40, seed=1)):
        world = int(worlds.test_ids[i % worlds.test_ids.size])
        result = planner.plan(s, g, TableOracle(worlds.X[world]), seed=i)
        statuses.add(result.status)
        exists = _free_path_exists(problem, world, s, g)
        if result.found:
            outcomes = result.outcomes()
            assert all(outcomes[int(e)] for e in result.edges)
            assert result.vertices[0] == s
            assert result.vertices[-1] == g
            assert result.cost == pytest.approx(float(prior.graph.lengths[result.edges].sum()))
            assert worlds.X[world, result.edges].all()
        else:
            assert result.status is PlanStatus.NO_PATH
            assert not exists, "said no path although the graph has a free one"
        assert len({c.edge for c in result.checks}) == result.num_checks
    assert PlanStatus.FOUND in statuses


def test_the_precomputed_tree_serves_its_query(problem: Problem, prior: WorldPrior) -> None:
    planner = Planner(prior)
    world = int(problem.require_worlds().test_ids[0])
    result = planner.plan(problem.start, problem.goal, TableOracle(problem.require_worlds().X[world]))  # type: ignore[arg-type]
    assert result.query == "tree:own"
    assert result.library_size == problem.num_paths
    other = planner.plan(0, 5, TableOracle(problem.require_worlds().X[world]))
    assert other.query == "online"


def test_a_repeated_online_query_says_its_model_came_from_the_cache(problem: Problem, prior: WorldPrior) -> None:
    planner = Planner(prior)
    row = problem.require_worlds().X[int(problem.require_worlds().test_ids[0])]
    first, again = (planner.plan(0, 5, TableOracle(row)) for _ in range(2))
    assert (first.query_cached, again.query_cached) == (False, True)
    assert [c.edge for c in first.checks] == [c.edge for c in again.checks]


def test_same_seed_same_checks(problem: Problem, prior: WorldPrior) -> None:
    worlds = problem.require_worlds()
    oracle_row = worlds.X[int(worlds.test_ids[2])]
    runs = [Planner(prior).plan(3, 40, TableOracle(oracle_row), seed=5) for _ in range(2)]
    assert [c.edge for c in runs[0].checks] == [c.edge for c in runs[1].checks]
    assert runs[0].status == runs[1].status


def test_blocked_library_falls_back_to_the_graph(problem: Problem, prior: WorldPrior) -> None:
    # A world in which every edge of every library path of the query is blocked, but a detour is free.
    planner = Planner(prior)
    s, g = problem.start, problem.goal
    assert s is not None
    assert g is not None
    library = planner.query_model(s, g).library
    assert library is not None
    # Block a small hitting set of the library (greedy: the edge on most unblocked paths, repeat).
    world = np.ones(problem.num_edges, dtype=bool)
    incidence = library.dense_incidence()
    alive = np.ones(library.num_paths, dtype=bool)
    while alive.any():
        edge = int(np.argmax(incidence[alive].sum(axis=0)))
        world[edge] = False
        alive &= ~incidence[:, edge]
    graph = problem.graph
    assert graph is not None
    assert ShortestPaths(GraphArcs(graph), graph.lengths).path(s, g, world) is not None
    result = planner.plan(s, g, TableOracle(world))
    assert result.found
    assert result.stage is PlanStage.GRAPH
    assert world[result.edges].all()
    assert any(c.stage == "graph" for c in result.checks)


def test_no_path_only_when_the_graph_is_cut(problem: Problem, prior: WorldPrior) -> None:
    planner = Planner(prior)
    graph = problem.graph
    assert graph is not None
    s = problem.start
    assert s is not None
    world = np.ones(problem.num_edges, dtype=bool)
    world[(graph.edges == s).any(axis=1)] = False  # every edge at the start is blocked
    result = planner.plan(s, problem.goal, TableOracle(world))  # type: ignore[arg-type]
    assert result.status is PlanStatus.NO_PATH
    assert "no free path" in result.reason
    at_start = set(np.flatnonzero((graph.edges == s).any(axis=1)).tolist())
    assert at_start <= {c.edge for c in result.checks}


@pytest.mark.parametrize("budget", [{"max_checks": 1}, {"time_budget_s": 1e-9}])
def test_budgets_end_with_their_own_status(problem: Problem, prior: WorldPrior, budget: dict[str, float]) -> None:
    world = np.ones(problem.num_edges, dtype=bool)
    result = Planner(prior).plan(problem.start, problem.goal, TableOracle(world), **budget)  # type: ignore[arg-type]
    assert result.status is PlanStatus.BUDGET_EXHAUSTED
    assert result.num_checks <= 1
    assert "budget" in result.reason


def test_the_check_budget_covers_both_stages(problem: Problem, prior: WorldPrior) -> None:
    planner = Planner(prior)
    s, g = problem.start, problem.goal
    world = np.zeros(problem.num_edges, dtype=bool)  # everything blocked: library then graph stage
    result = planner.plan(s, g, TableOracle(world), max_checks=25)  # type: ignore[arg-type]
    assert result.num_checks <= 25
    assert result.status in (PlanStatus.BUDGET_EXHAUSTED, PlanStatus.NO_PATH)


@pytest.mark.parametrize(
    ("start", "fragment"),
    [
        (10_000, "outside the graph"),
        (-1, "outside the graph"),
        ([np.nan, 0.5], "NaN"),
        ([0.1, 0.2, 0.3], "2 values"),
        ([5.0, 5.0], "snap tolerance"),
        ("a", "vertex id or a state"),
        (True, "boolean"),
    ],
)
def test_bad_endpoints_are_refused_with_a_reason(prior: WorldPrior, start: object, fragment: str) -> None:
    result = Planner(prior).plan(start, 1, TableOracle(np.ones(prior.graph.num_edges, dtype=bool)))  # type: ignore[arg-type]
    assert result.status is PlanStatus.REFUSED
    assert fragment in result.reason
    assert result.num_checks == 0


def test_states_snap_to_their_vertex(prior: WorldPrior) -> None:
    states = prior.graph.vertex_states
    assert states is not None
    planner = Planner(prior)
    near = states[7] + planner.snap_tolerance * 0.1
    assert planner.resolve(near, states[9]) == (7, 9)


def test_start_equal_goal_is_the_empty_path(prior: WorldPrior) -> None:
    result = Planner(prior).plan(4, 4, TableOracle(np.ones(prior.graph.num_edges, dtype=bool)))
    assert result.found
    assert result.stage is PlanStage.TRIVIAL
    assert result.edges.size == 0
    assert result.vertices.tolist() == [4]


def test_every_plan_policy_runs(problem: Problem, prior: WorldPrior) -> None:
    worlds = problem.require_worlds()
    row = worlds.X[int(worlds.test_ids[0])]
    for name in PLAN_POLICIES:
        result = Planner(prior).plan(2, 30, TableOracle(row), policy=name, seed=1)
        assert result.status in (PlanStatus.FOUND, PlanStatus.NO_PATH), name


def test_bad_arguments_raise(prior: WorldPrior) -> None:
    planner = Planner(prior)
    oracle = TableOracle(np.ones(prior.graph.num_edges, dtype=bool))
    with pytest.raises(ProblemError, match="known:"):
        planner.plan(0, 1, oracle, policy="nope")
    with pytest.raises(ProblemError, match="max_checks"):
        planner.plan(0, 1, oracle, max_checks=0)
    with pytest.raises(ProblemError, match="time_budget_s"):
        planner.plan(0, 1, oracle, time_budget_s=float("nan"))


def test_cache_is_bounded_lru(prior: WorldPrior) -> None:
    planner = Planner(prior, cache_size=2)
    for q in [(0, 5), (1, 6), (0, 5), (2, 7)]:
        planner.query_model(*q)
    assert planner.cached_queries() == [(0, 5), (2, 7)]
    assert set(planner.memory_bytes()) == {"worlds", "graph", "trees", "query_cache"}


def test_a_prior_from_a_tree_file_serves_only_its_query(problem: Problem, prior: WorldPrior) -> None:
    legacy = dataclasses.replace(prior, worlds=None)
    planner = Planner(legacy)
    world = np.ones(problem.num_edges, dtype=bool)
    assert planner.plan(problem.start, problem.goal, TableOracle(world)).found  # type: ignore[arg-type]
    other = planner.plan(0, 5, TableOracle(world))
    assert other.status is PlanStatus.REFUSED
    assert "drd build-tree --dataset" in other.reason


def test_a_query_no_training_world_connects_goes_straight_to_the_graph() -> None:
    # Path graph 0-1-2 plus a bypass 0-3-2 that is blocked in every training world.
    graph = ExplicitGraph(np.array([[0, 1], [1, 2], [0, 3], [3, 2]]), np.ones(4), 4)
    worlds = np.array([[True, False, False, True], [False, True, True, False]])
    library = PathLibrary((np.array([0, 1]),), 4)
    problem = Problem(
        "tiny",
        library,
        np.ones(4),
        graph,
        0,
        2,
        WorldDatabase(worlds, library.valid_paths(worlds), [0, 1], []),
    )
    planner = Planner(prior_from_problem(problem, domain="planar"))
    assert planner.query_model(0, 2).library is None
    result = planner.plan(0, 2, TableOracle(np.ones(4, dtype=bool)))
    assert result.found
    assert result.stage is PlanStage.GRAPH


def test_a_precomputed_tree_uses_its_own_leaf_setting_and_other_queries_the_priors(
    problem: Problem, prior: WorldPrior
) -> None:
    from drd_planner import LeafSetting

    worlds = problem.require_worlds()
    oracle = TableOracle(worlds.X[int(worlds.test_ids[0])])
    own = prior.trees[0]
    bisect_prior = dataclasses.replace(prior, eta=1.0)

    def first_stage(planner: Planner, start: int, goal: int) -> str:
        return planner.plan(start, goal, oracle, seed=0).checks[0].stage

    # eta 1 everywhere: BiSECt from the first check.
    assert first_stage(Planner(bisect_prior), own.start, own.goal) == "bisect"
    # The tree's own eta 0.05 walks its tree; another query keeps the prior's eta 1.
    with_leaf = dataclasses.replace(bisect_prior, trees=(dataclasses.replace(own, leaf=LeafSetting(0.05, None)),))
    planner = Planner(with_leaf)
    assert first_stage(planner, own.start, own.goal) == "tree"
    other = next((s, g) for s, g in _queries(problem, 50, seed=3) if (s, g) != (own.start, own.goal))
    result = planner.plan(*other, oracle, seed=0)
    assert result.query == "online"
    assert all(c.stage != "tree" for c in result.checks)
    # set_leaf overrides both (the validation's use).
    planner.set_leaf(1.0, None)
    assert first_stage(planner, own.start, own.goal) == "bisect"
    planner.set_leaf(0.05, None)
    assert planner.plan(*other, oracle, seed=0).checks[0].stage == "tree"


def test_new_queries_use_the_priors_region_rule(problem: Problem, prior: WorldPrior) -> None:
    # Without the probe, so that a new query's model has its tree at once.
    planner = Planner(dataclasses.replace(prior, region_rule="per_check"), probe_probability=None)
    model = planner.query_model(3, 40)
    assert model.tree is not None
    assert model.tree.region_rule == "per_check"
    assert planner.query_model(problem.start, problem.goal).tree.region_rule == "probability"  # type: ignore[arg-type, union-attr]
    # Changing the rule drops the cached online trees, not the precomputed one.
    planner.set_leaf(0.2, None, region_rule="probability")
    again = planner.query_model(3, 40)
    assert again is not model
    assert again.tree is not None
    assert again.tree.region_rule == "probability"
    with pytest.raises(ProblemError, match="known: probability, per_check"):
        planner.set_leaf(0.2, None, region_rule="cheapest")
    # Both rules verify every edge of the path they return.
    worlds = problem.require_worlds()
    for rule in ("probability", "per_check"):
        planner.set_leaf(0.2, None, region_rule=rule)
        for world in worlds.test_ids[:5]:
            result = planner.plan(3, 40, TableOracle(worlds.X[int(world)]), seed=0)
            if result.found:
                outcomes = result.outcomes()
                assert all(outcomes[int(e)] for e in result.edges)


def test_forgotten_queries_are_new_again_and_the_query_graph_is_the_priors(problem: Problem, prior: WorldPrior) -> None:
    planner = Planner(prior)
    assert problem.worlds is not None
    row = problem.worlds.X[int(problem.worlds.test_ids[0])]
    first = planner.plan(3, 40, TableOracle(row))
    planner.forget_queries()
    again = planner.plan(3, 40, TableOracle(row))
    assert not again.query_cached
    assert [c.edge for c in again.checks] == [c.edge for c in first.checks]
    assert planner.plan(3, 40, TableOracle(row)).query_cached
    query = planner.query_graph(3, 40)
    assert query.graph is prior.graph
    assert (query.start, query.goal) == (3, 40)
    assert not query.connected
