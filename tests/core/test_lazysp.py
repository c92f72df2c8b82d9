"""LazySP on the full graph: exact check orders of every selector, re-planning, disconnection, the
check budget, directed versus undirected edges, WeightSamp's batched sampler, and a real dataset."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from conftest import gccd_folder
from scipy.sparse.csgraph import breadth_first_order, dijkstra

from drd_planner.core.bisect import bias_from_worlds
from drd_planner.core.episode import EpisodeResult, GraphPathPolicy, TableOracle, run_episode
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.lazysp import DEFAULT_MAX_CHECKS, GraphArcs, LazySP, LazySPSettings, bisection_position
from drd_planner.core.library import PathLibrary
from drd_planner.core.policies import POLICIES, PolicyContext, graph_policies
from drd_planner.core.status import PlanCause, PlanStatus
from drd_planner.data.gccd import load_gccd_folder
from drd_planner.exceptions import ProblemError

# A 3 x 3 grid, start 0, goal 8:
#
#   6 -e4- 7 -e5- 8
#   e7     e9     e11
#   3 -e2- 4 -e3- 5
#   e6     e8     e10
#   0 -e0- 1 -e1- 2
#
# Lengths: e0, e1, e10, e11 = 1.0; other horizontals 1.2; other verticals 1.1. Edges 10 and 3 are stored
# reversed, so an undirected search must traverse them against their stored orientation.
# Shortest path A = [e0, e1, e10, e11] (4.0). With e10 blocked: B = [e0, e8, e3, e11] (4.3), unique
# (0-1-4-7-8 is 4.4, 0-3-4-5-8 4.5).
GRID_EDGES = [(0, 1), (1, 2), (3, 4), (5, 4), (6, 7), (7, 8), (0, 3), (3, 6), (1, 4), (4, 7), (5, 2), (5, 8)]
GRID_LENGTHS = [1.0, 1.0, 1.2, 1.2, 1.2, 1.2, 1.1, 1.1, 1.1, 1.1, 1.0, 1.0]
PATH_A = [0, 1, 10, 11]
PATH_B = [0, 8, 3, 11]


def grid(directed: bool = False) -> ExplicitGraph:
    return ExplicitGraph(np.array(GRID_EDGES), np.array(GRID_LENGTHS), 9, directed=directed)


def world(*blocked: int) -> np.ndarray:
    x = np.ones(len(GRID_EDGES), dtype=bool)
    x[list(blocked)] = False
    return x


def run(policy: LazySP, x: np.ndarray, library: PathLibrary | None = None) -> EpisodeResult:
    lib = library or PathLibrary.from_sequences([PATH_A], len(GRID_EDGES))
    return run_episode(lib, np.ones(len(GRID_EDGES)), policy, TableOracle(x))


@pytest.mark.parametrize(
    ("selector", "expected"),
    [
        # A: 0, 1 free, 10 blocked -> B: 0 already checked, then 8, 3, 11.
        ("forward", [0, 1, 10, 8, 3, 11]),
        # A: 11 free, 10 blocked -> B (11 checked): 3, 8, 0.
        ("reverse", [11, 10, 3, 8, 0]),
        # fwd 0, rev 11, fwd 1, rev 10 (blocked) -> B: fwd 8, rev 3.
        ("alternate", [0, 11, 1, 10, 8, 3]),
        # A unchecked: distances [1, 2, 2, 1] -> e1; [1, 0, 1, 1] -> e0; [0, 0, 1, 1] -> e10 (blocked);
        # B with e0 checked: [0, 1, 2, 1] -> e3; [0, 1, 0, 1] -> e8; then e11.
        ("bisection", [1, 0, 10, 3, 8, 11]),
    ],
)
def test_selector_check_orders_on_the_grid(selector: str, expected: list[int]) -> None:
    result = run(LazySP(grid(), 0, 8, LazySPSettings(selector=selector)), world(10))
    assert [c.edge for c in result.checks] == expected
    assert result.status is PlanStatus.FOUND
    assert result.path_index is None  # LazySP's own path, not a library path
    np.testing.assert_array_equal(result.path_edges, PATH_B)
    assert all(c.stage == "lazysp" for c in result.checks)


def test_free_world_checks_exactly_the_shortest_path() -> None:
    for selector in ("forward", "reverse", "alternate", "bisection", "weightsamp", "balanced"):
        result = run(LazySP(grid(), 0, 8, LazySPSettings(selector=selector, seed=1)), world())
        assert sorted(c.edge for c in result.checks) == sorted(PATH_A)
        np.testing.assert_array_equal(result.path_edges, PATH_A)


def test_replans_until_the_shortest_feasible_path() -> None:
    # e10 and e8 blocked: A fails at e10, B at e8; without both, vertex 4 is reached via 3 and the
    # shortest path is 0-3-4-5-8 = [e6, e2, e3, e11] (4.5; 0-3-6-7-8 and 0-3-4-7-8 are 4.6).
    result = run(LazySP(grid(), 0, 8), world(10, 8))
    assert [c.edge for c in result.checks] == [0, 1, 10, 8, 6, 2, 3, 11]
    np.testing.assert_array_equal(result.path_edges, [6, 2, 3, 11])


def test_disconnected_start_ends_with_no_free_path() -> None:
    # A: e0 blocked -> 0-3-4-5-8 = [e6, e2, e3, e11]: e6 blocked -> start is cut off.
    result = run(LazySP(grid(), 0, 8), world(0, 6))
    assert [c.edge for c in result.checks] == [0, 6]
    assert result.status is PlanStatus.NO_PATH
    assert result.path_edges is None
    assert result.blocked_evidence is None
    assert not result.success


def test_does_not_stop_on_a_proven_library_path() -> None:
    # Forward proves library path [e0, e1] after two checks; LazySP goes on to its own path.
    lib = PathLibrary.from_sequences([[0, 1], PATH_A], len(GRID_EDGES))
    result = run(LazySP(grid(), 0, 8), world(10), library=lib)
    assert result.num_checks == 6
    assert result.path_index is None
    np.testing.assert_array_equal(result.path_edges, PATH_B)


def test_check_budget_reports_max_checks() -> None:
    result = run(LazySP(grid(), 0, 8, LazySPSettings(max_checks=3)), world(10))
    assert (result.status, result.cause) == (PlanStatus.BUDGET_EXHAUSTED, PlanCause.CHECK_BUDGET)
    assert result.num_checks == 3
    assert not result.success
    assert result.path_edges is None
    # The budget does not cut an episode whose path is verified by the last allowed check.
    assert run(LazySP(grid(), 0, 8, LazySPSettings(max_checks=4)), world()).status is PlanStatus.FOUND


def test_default_budget_is_1000_checks() -> None:
    # 600 two-edge routes s - m_i - g (route i slightly longer than route i-1): each one's first edge
    # is free and its second blocked, so forward LazySP needs 1200 checks and stops at 1000.
    routes = 600
    edges = [(0, 2 + i) for i in range(routes)] + [(2 + i, 1) for i in range(routes)]
    lengths = [1.0 + 1e-3 * i for i in range(routes)] + [1.0] * routes
    graph = ExplicitGraph(np.array(edges), np.array(lengths), routes + 2)
    x = np.array([True] * routes + [False] * routes)
    policy = LazySP(graph, 0, 1)
    assert policy.max_checks == DEFAULT_MAX_CHECKS == 1000
    lib = PathLibrary.from_sequences([[0, routes]], len(edges))
    result = run_episode(lib, np.ones(len(edges)), policy, TableOracle(x))
    assert (result.status, result.cause) == (PlanStatus.BUDGET_EXHAUSTED, PlanCause.CHECK_BUDGET)
    assert result.num_checks == 1000
    assert [c.edge for c in result.checks[:4]] == [0, routes, 1, routes + 1]


def test_directed_edges_are_one_way() -> None:
    # e0 = 0 -> 1 (1.0), e1 = 2 -> 1 (1.0), e2 = 0 -> 2 (5.0); goal 2.
    edges, lengths = np.array([(0, 1), (2, 1), (0, 2)]), np.array([1.0, 1.0, 5.0])
    lib = PathLibrary.from_sequences([[2]], 3)
    undirected = ExplicitGraph(edges, lengths, 3, directed=False)
    directed = ExplicitGraph(edges, lengths, 3, directed=True)
    free = np.ones(3, dtype=bool)
    np.testing.assert_array_equal(
        run_episode(lib, np.ones(3), LazySP(undirected, 0, 2), TableOracle(free)).path_edges, [0, 1]
    )
    np.testing.assert_array_equal(
        run_episode(lib, np.ones(3), LazySP(directed, 0, 2), TableOracle(free)).path_edges, [2]
    )
    # On the directed grid, edges 3 (5 -> 4) and 10 (5 -> 2) only run one way, so A and B are not
    # paths; the shortest is 0 -> 1 -> 4 -> 7 -> 8 = [e0, e8, e9, e5] (4.4).
    np.testing.assert_array_equal(LazySP(grid(directed=True), 0, 8).proposed_path(), [0, 8, 9, 5])


def test_bisection_position_matches_lemur() -> None:
    assert bisection_position(np.array([False] * 4)) == 1
    assert bisection_position(np.array([False] * 5)) == 2
    assert bisection_position(np.array([True, False, False, False, False, True])) == 2
    assert bisection_position(np.array([False])) == 0


def test_weightsamp_batched_counts_equal_one_search_per_sample() -> None:
    graph = grid()
    policy = LazySP(graph, 0, 8, LazySPSettings(selector="weightsamp", nsamps=150, seed=5))
    policy.observe(0, True)
    policy.observe(10, False)
    counts = policy.shortest_path_counts()
    # Replay the same draws (batches of 100 and 50) one sample at a time with deletion.
    rng = np.random.default_rng(5)
    arcs = GraphArcs(graph)
    lengths = np.array(GRID_LENGTHS)
    unknown = np.ones(len(GRID_EDGES), dtype=bool)
    unknown[[0, 10]] = False
    known = lengths.copy()
    known[10] = np.inf
    want = np.zeros(len(GRID_EDGES), dtype=np.int64)
    for k in (100, 50):
        for draw in rng.random((k, len(GRID_EDGES))):
            w = np.where(unknown, np.where(draw > 0.5, np.inf, 1.0 + draw / 0.5), known)
            path = arcs.shortest_path(0, 8, w)
            if path is not None:
                want[path] += 1
    np.testing.assert_array_equal(counts, want)
    assert counts[10] == 0
    assert counts.sum() > 0


def test_weightsamp_is_seeded_and_picks_the_most_sampled_edge() -> None:
    orders = []
    for seed in (3, 3, 4):
        result = run(LazySP(grid(), 0, 8, LazySPSettings(selector="weightsamp", nsamps=50, seed=seed)), world(10))
        np.testing.assert_array_equal(result.path_edges, PATH_B)
        orders.append([c.edge for c in result.checks])
    assert orders[0] == orders[1]
    policy = LazySP(grid(), 0, 8, LazySPSettings(selector="weightsamp", nsamps=50, seed=9))
    first = policy.select()
    counts = LazySP(grid(), 0, 8, LazySPSettings(selector="weightsamp", nsamps=50, seed=9)).shortest_path_counts()[
        PATH_A
    ]
    assert first == PATH_A[len(PATH_A) - 1 - int(np.argmax(counts[::-1]))]  # ties go to the later edge


def test_registry_and_missing_graph() -> None:
    assert {"lazysp", "lazysp_reverse", "lazysp_alternate", "lazysp_bisection", "lazysp_weightsamp"} <= set(
        graph_policies()
    )
    lib = PathLibrary.from_sequences([PATH_A], len(GRID_EDGES))
    theta = np.full(len(GRID_EDGES), 0.5)
    bare = PolicyContext(lib, np.ones(len(GRID_EDGES)), theta, None, seed=0)
    no_goal = PolicyContext(lib, np.ones(len(GRID_EDGES)), theta, None, seed=0, graph=grid(), start=0)
    full = PolicyContext(lib, np.ones(len(GRID_EDGES)), theta, None, seed=0, graph=grid(), start=0, goal=8)
    for name in ("lazysp", "lazysp_reverse", "lazysp_alternate", "lazysp_bisection", "lazysp_weightsamp"):
        with pytest.raises(ProblemError, match="graph"):
            POLICIES[name](bare)
        with pytest.raises(ProblemError, match="goal"):
            POLICIES[name](no_goal)
        policy = POLICIES[name](full)
        assert policy.name == name
        assert isinstance(policy, GraphPathPolicy)
    with pytest.raises(ProblemError, match="selector"):
        LazySP(grid(), 0, 8, LazySPSettings(selector="sideways"))
    with pytest.raises(ProblemError, match="start"):
        LazySP(grid(), 9, 8)


def shortest_feasible_length(graph: ExplicitGraph, x: np.ndarray, start: int, goal: int) -> float:
    e = graph.edges[x]
    w = graph.lengths[x]
    n = graph.num_vertices
    rows, cols = (e[:, 0], e[:, 1]) if graph.directed else (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])
    weights = w if graph.directed else np.r_[w, w]
    csr = sp.csr_array((weights, (rows, cols)), shape=(n, n))
    return float(dijkstra(csr, directed=True, indices=start)[goal])


def test_dataset_smoke_lazysp_returns_the_shortest_feasible_path() -> None:
    problem = load_gccd_folder(gccd_folder("dataset_2d_1"))
    assert problem.graph is not None
    assert problem.start is not None
    assert problem.goal is not None
    worlds = problem.require_worlds()
    theta = bias_from_worlds(worlds.X[worlds.train_ids])
    for name in ("lazysp", "lazysp_reverse", "lazysp_alternate", "lazysp_bisection", "lazysp_weightsamp"):
        limit = 2 if name == "lazysp_weightsamp" else 5
        for k, w in enumerate(worlds.test_ids[:limit]):
            x = worlds.X[w]
            ctx = PolicyContext(
                problem.library,
                problem.edge_costs,
                theta,
                None,
                k,
                graph=problem.graph,
                start=problem.start,
                goal=problem.goal,
            )
            result = run_episode(problem.library, problem.edge_costs, POLICIES[name](ctx), TableOracle(x))
            edges = [c.edge for c in result.checks]
            assert len(set(edges)) == len(edges)
            assert result.status is PlanStatus.FOUND, name
            path = result.path_edges
            assert path is not None
            assert all(x[int(e)] for e in path)
            assert set(path.tolist()) <= set(edges)
            # a connected start-goal walk
            ends = problem.graph.edges[path]
            seq = [problem.start]
            for a, b in ends:
                seq.append(int(b) if seq[-1] == a else int(a))
                assert seq[-2] in (a, b)
            assert seq[-1] == problem.goal
            assert problem.graph.lengths[path].sum() == pytest.approx(
                shortest_feasible_length(problem.graph, x, problem.start, problem.goal)
            )


def _searched_reach(pairs: np.ndarray, outcomes: dict[int, bool], n: int, directed: bool) -> tuple[int, int]:
    """The two known-free regions' sizes by a breadth-first search of the whole graph's checked-free arcs."""
    arcs = [(int(pairs[e, 0]), int(pairs[e, 1])) for e, f in outcomes.items() if f]
    if not directed:
        arcs += [(v, u) for u, v in arcs]
    rows, cols = (np.array([a[i] for a in arcs], dtype=np.int64) for i in (0, 1))
    adjacency = sp.csr_array((np.ones(rows.size), (rows, cols)), shape=(n, n))
    ahead = breadth_first_order(adjacency, 0, directed=True, return_predecessors=False)
    behind = breadth_first_order(adjacency.T.tocsr(), n - 1, directed=True, return_predecessors=False)
    return int(ahead.size), int(behind.size)


@pytest.mark.parametrize("directed", [False, True])
def test_the_known_free_reach_is_a_search_over_the_checked_free_edges(directed: bool) -> None:
    """The balanced selector's regions equal a breadth-first search of the whole graph's checked-free arcs."""
    rng = np.random.default_rng(3)
    n = 60
    drawn = rng.integers(n, size=(600, 2))  # self-loops kept: they reach nothing new
    keys = drawn if directed else np.sort(drawn, axis=1)
    pairs = drawn[np.unique(keys, axis=0, return_index=True)[1]][:400]
    graph = ExplicitGraph(pairs, np.ones(len(pairs)), num_vertices=n, directed=directed)
    policy = LazySP(graph, 0, n - 1, LazySPSettings(selector="balanced"))
    outcomes: dict[int, bool] = {}
    for edge in rng.permutation(len(pairs))[:150].tolist():
        free = bool(rng.random() < 0.7)
        policy.observe(edge, free)
        outcomes[edge] = free
        assert policy.known_free_reach() == _searched_reach(pairs, outcomes, n, directed)
    # an edge checked free and then blocked (a later outcome wins) leaves the regions
    edge = next(e for e, f in outcomes.items() if f)
    policy.observe(edge, False)
    outcomes[edge] = False
    assert policy.known_free_reach() == _searched_reach(pairs, outcomes, n, directed)


def test_balanced_checks_from_the_walled_in_end() -> None:
    # Nothing checked: both known-free regions are one vertex, so it starts forward (e0 of path A). Then
    # the start's region has grown and the goal's has not: it checks from the goal's end.
    policy = LazySP(grid(), 0, 8, LazySPSettings(selector="balanced"))
    assert policy.select() == 0
    policy.observe(0, True)
    assert policy.known_free_reach() == (2, 1)
    assert policy.select() == 11
    result = run(LazySP(grid(), 0, 8, LazySPSettings(selector="balanced")), world(0, 6))
    assert result.status is PlanStatus.NO_PATH
