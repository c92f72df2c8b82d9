"""The learned LazySP selectors: posterior ranking and its update, kappa shrinkage, Delta-length and
bridges, exact episodes against brute force, determinism, the registry, and a real dataset."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from conftest import gccd_folder
from scipy.sparse.csgraph import dijkstra

from drd_planner.bench.lazysp_learned import (
    LEARNED_LAZYSP_POLICIES,
    PosteriorLazySP,
    PosteriorSettings,
    all_edge_outcomes,
    delta_choice,
)
from drd_planner.core.episode import EpisodeResult, GraphPathPolicy, TableOracle, run_episode
from drd_planner.core.graph import ExplicitGraph
from drd_planner.core.lazysp import GraphArcs
from drd_planner.core.library import PathLibrary
from drd_planner.core.policies import DEFAULT_PSEUDO_COUNT, POLICIES, PolicyContext, graph_policies
from drd_planner.core.status import PlanStatus
from drd_planner.data.gccd import load_gccd_folder
from drd_planner.exceptions import ProblemError

TINY = 1e-9  # kappa close to 0: the plain consistent-world fraction

# A chain 0 -e0- 1 -e1- 2 -e2- 3 (length 1 each) and a long detour 0 -e3- 3 (10).
CHAIN = ExplicitGraph(np.array([(0, 1), (1, 2), (2, 3), (0, 3)]), np.array([1.0, 1.0, 1.0, 10.0]), 4)
# Training worlds over e0..e3 (True = free). Blocked fractions 2/6, 3/6, 2/6, 0.
CHAIN_WORLDS = np.array(
    [
        [1, 0, 1, 1],
        [1, 0, 1, 1],
        [0, 0, 1, 1],
        [1, 1, 0, 1],
        [0, 1, 1, 1],
        [1, 1, 0, 1],
    ],
    dtype=bool,
)

# The chain 0 -e0- 1 -e1- 2 -e2- 3 (length 1 each) with one detour around each edge:
# e0: 0 -e3- 4 -e4- 1 (1.0 + 0.5, Delta 0.5); e1: 1 -e5- 5 -e6- 2 (1.5 + 1.5, Delta 2);
# e2: 2 -e7- 6 -e8- 3 (1.0 + 1.0, Delta 1). Deleting e7 makes e2 a bridge.
DETOURS = ExplicitGraph(
    np.array([(0, 1), (1, 2), (2, 3), (0, 4), (4, 1), (1, 5), (5, 2), (2, 6), (6, 3)]),
    np.array([1.0, 1.0, 1.0, 1.0, 0.5, 1.5, 1.5, 1.0, 1.0]),
    7,
)
# World A: e1, e7 blocked; world B: e0, e2 blocked. Every chain edge and e7 blocked half the time.
DETOUR_WORLDS = np.ones((2, 9), dtype=bool)
DETOUR_WORLDS[0, [1, 7]] = False
DETOUR_WORLDS[1, [0, 2]] = False


def policy(graph: ExplicitGraph, worlds: np.ndarray, *, delta: bool = False, kappa: float = TINY) -> PosteriorLazySP:
    return PosteriorLazySP(graph, 0, 3, all_edge_outcomes(worlds), PosteriorSettings(kappa, delta))


def episode(pol: PosteriorLazySP, x: np.ndarray) -> EpisodeResult:
    lib = PathLibrary.from_sequences([[0]], x.size)
    return run_episode(lib, np.ones(x.size), pol, TableOracle(x))


def test_posterior_picks_the_most_often_blocked_edge_and_updates() -> None:
    pol = policy(CHAIN, CHAIN_WORLDS)
    np.testing.assert_array_equal(pol.proposed_path(), [0, 1, 2])
    np.testing.assert_allclose(pol.blocked_probability(), [2 / 6, 3 / 6, 2 / 6, 0.0], atol=1e-8)
    assert pol.select() == 1  # the middle edge: neither forward nor reverse
    pol.observe(1, True)  # drops the three worlds with e1 blocked
    assert pol.num_consistent == 3
    np.testing.assert_allclose(pol.blocked_probability()[[0, 2]], [1 / 3, 2 / 3], atol=1e-8)
    assert pol.select() == 2  # before the update e0 and e2 tied (and e0 would have won)


def test_ties_go_to_the_earlier_path_edge() -> None:
    worlds = CHAIN_WORLDS.copy()
    worlds[:, 1] = True  # e1 never blocked: e0 and e2 tie at 2/6
    assert policy(CHAIN, worlds).select() == 0
    worlds[0, 2] = False  # now e2 is ahead: 3/6
    assert policy(CHAIN, worlds).select() == 2


def test_kappa_shrinks_toward_the_training_marginal() -> None:
    # After e1 free: 3 consistent worlds, e2 blocked in 2 of them; marginal P(e2 blocked) = 2/6.
    for kappa, expected in ((TINY, 2 / 3), (6.0, 1 - (1 + 6.0 * 4 / 6) / (3 + 6.0)), (1e9, 2 / 6)):
        pol = policy(CHAIN, CHAIN_WORLDS, kappa=kappa)
        pol.observe(1, True)
        assert pol.blocked_probability()[2] == pytest.approx(expected, abs=1e-7), kappa
    # No consistent world left (e3 is never blocked in training): the marginal, not 0/1.
    pol = policy(CHAIN, CHAIN_WORLDS)
    pol.observe(3, False)
    assert pol.num_consistent == 0
    np.testing.assert_allclose(pol.blocked_probability()[:3], [2 / 6, 3 / 6, 2 / 6], atol=1e-8)
    with pytest.raises(ProblemError, match="pseudo_count"):
        policy(CHAIN, CHAIN_WORLDS, kappa=0.0)


def test_delta_prefers_the_edge_whose_loss_lengthens_the_path_most() -> None:
    pol = policy(DETOURS, DETOUR_WORLDS, delta=True)
    np.testing.assert_array_equal(pol.proposed_path(), [0, 1, 2])
    np.testing.assert_allclose(pol.delta_lengths(np.array([0, 1, 2])), [0.5, 2.0, 1.0])
    assert pol.select() == 1  # equal posteriors (1/2): the largest Delta
    assert policy(DETOURS, DETOUR_WORLDS).select() == 0  # the plain posterior: first of the tie


def test_a_bridge_ranks_first() -> None:
    # e7 blocked leaves world A: P(e1 blocked) ~ 1 with Delta 2, P(e2 blocked) ~ 0 but e2 is now a
    # bridge (Delta inf), so it is checked first.
    pol = policy(DETOURS, DETOUR_WORLDS, delta=True)
    pol.observe(7, False)
    assert pol.num_consistent == 1
    np.testing.assert_array_equal(pol.delta_lengths(np.array([0, 1, 2])), [0.5, 2.0, np.inf])
    assert pol.blocked_probability()[2] < 1e-6 < 1 - 1e-6 < pol.blocked_probability()[1]
    assert pol.select() == 2


def test_delta_choice_rules() -> None:
    inf = np.inf
    assert delta_choice(np.array([0.2, 0.9, 0.5]), np.array([inf, 1.0, inf])) == 2  # bridges by posterior
    assert delta_choice(np.array([0.2, 0.9, 0.2]), np.array([inf, 1.0, inf])) == 0  # then earlier
    assert delta_choice(np.array([0.3, 0.6, 0.6]), np.array([2.0, 1.0, 1.0])) == 1  # tie: posterior
    assert delta_choice(np.array([0.5, 0.5]), np.array([1.0, 1.0 + 1e-12])) == 0  # rounding is a tie
    assert delta_choice(np.array([0.1, 0.7, 0.2]), np.zeros(3)) == 1  # all zero: highest posterior
    assert delta_choice(np.array([0.1, 0.2, 0.25]), np.array([3.0, 1.0, 1.4])) == 2  # 0.35 > 0.3
    assert delta_choice(np.array([0.1, 0.2, 0.2]), np.array([3.0, 1.0, 1.4])) == 0  # 0.3 > 0.28


def grid(size: int) -> ExplicitGraph:
    """size x size 4-connected grid, vertex r * size + c, lengths from a seeded draw in [1, 2)."""
    ids = np.arange(size * size).reshape(size, size)
    edges = np.concatenate(
        [np.c_[ids[:, :-1].ravel(), ids[:, 1:].ravel()], np.c_[ids[:-1, :].ravel(), ids[1:, :].ravel()]]
    )
    lengths = 1.0 + np.random.default_rng(0).random(len(edges))
    return ExplicitGraph(edges, lengths, size * size)


def shortest_length(graph: ExplicitGraph, keep: np.ndarray, start: int, goal: int) -> float:
    """Shortest start-goal length over the edges in ``keep`` (inf when cut off)."""
    e, w, n = graph.edges[keep], graph.lengths[keep], graph.num_vertices
    rows, cols = (e[:, 0], e[:, 1]) if graph.directed else (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])
    csr = sp.csr_array((w if graph.directed else np.r_[w, w], (rows, cols)), shape=(n, n))
    return float(dijkstra(csr, directed=True, indices=start)[goal])


def test_deletion_lengths_match_one_search_per_deletion() -> None:
    graph = grid(5)
    arcs = GraphArcs(graph)
    weights = graph.lengths.copy()
    weights[[3, 17]] = np.inf
    edges = np.array([0, 5, 12, 30, 39])
    base, lengths = arcs.deletion_lengths(0, 24, weights, edges)
    keep = np.isfinite(weights)
    assert base == pytest.approx(shortest_length(graph, keep, 0, 24))
    for e, got in zip(edges, lengths, strict=True):
        k = keep.copy()
        k[e] = False
        assert got == pytest.approx(shortest_length(graph, k, 0, 24))
    # Cutting the goal off (its two edges) gives inf.
    goal_edges = np.flatnonzero((graph.edges == 24).any(axis=1))
    weights[goal_edges[0]] = np.inf
    assert arcs.deletion_lengths(0, 24, weights, goal_edges[1:])[1][0] == np.inf


def brute_force_choice(
    graph: ExplicitGraph,
    path: np.ndarray,
    worlds: np.ndarray,
    seen: dict[int, bool],
    kappa: float,
    delta: bool,
) -> int:
    """The selector's rule recomputed from scratch: consistent-world counts, one search per deletion."""
    cand = [int(e) for e in path if int(e) not in seen]
    consistent = np.ones(len(worlds), dtype=bool)
    for e, f in seen.items():
        consistent &= worlds[:, e] == f
    c = worlds[consistent]
    if len(c) == 0:
        c = np.zeros((0, worlds.shape[1]), dtype=bool)
    post = 1 - (c[:, cand].sum(axis=0) + kappa * worlds[:, cand].mean(axis=0)) / (len(c) + kappa)
    if not delta:
        return cand[int(np.argmax(post))]
    keep = np.ones(graph.num_edges, dtype=bool)
    keep[[e for e, f in seen.items() if not f]] = False
    base = shortest_length(graph, keep, 0, 35)
    growth = []
    for e in cand:
        k = keep.copy()
        k[e] = False
        growth.append(shortest_length(graph, k, 0, 35) - base)
    return cand[delta_choice(post, np.maximum(np.array(growth), 0.0))]


@pytest.mark.parametrize("delta", [False, True])
def test_episodes_are_exact_lazysp_runs(delta: bool) -> None:
    """Random worlds on a grid: every selection is the rule's, the path is the shortest feasible one."""
    graph = grid(6)
    rng = np.random.default_rng(11)
    worlds = rng.random((40, graph.num_edges)) > 0.3
    outcomes = all_edge_outcomes(worlds)
    kappa = 3.0
    for test in rng.random((6, graph.num_edges)) > 0.3:
        pol = PosteriorLazySP(graph, 0, 35, outcomes, PosteriorSettings(kappa, delta))
        seen: dict[int, bool] = {}
        while (edge := pol.select()) is not None:
            path = pol.proposed_path()
            assert path is not None
            assert edge == brute_force_choice(graph, path, worlds, seen, kappa, delta)
            seen[edge] = bool(test[edge])
            pol.observe(edge, seen[edge])
        path = pol.proposed_path()
        best = shortest_length(graph, test, 0, 35)
        if path is None:
            assert best == np.inf
        else:
            assert all(seen.get(int(e)) is True for e in path)
            assert graph.lengths[path].sum() == pytest.approx(best)


@pytest.mark.parametrize("delta", [False, True])
def test_episode_outcomes_and_determinism(delta: bool) -> None:
    free = np.ones(9, dtype=bool)
    runs = [episode(policy(DETOURS, DETOUR_WORLDS, delta=delta), free) for _ in range(2)]
    assert [c.edge for c in runs[0].checks] == [c.edge for c in runs[1].checks]
    assert runs[0].status is PlanStatus.FOUND
    np.testing.assert_array_equal(runs[0].path_edges, [0, 1, 2])
    assert sorted(c.edge for c in runs[0].checks) == [0, 1, 2]
    # e2 and its detour blocked: start and goal are disconnected.
    cut = free.copy()
    cut[[2, 7]] = False
    result = episode(policy(DETOURS, DETOUR_WORLDS, delta=delta), cut)
    assert result.status is PlanStatus.NO_PATH
    assert result.path_edges is None
    assert {2, 7} <= {c.edge for c in result.checks if not c.free}


def test_registry_needs_the_training_worlds() -> None:
    assert set(LEARNED_LAZYSP_POLICIES) == {"lazysp_posterior", "lazysp_posterior_delta"}
    assert set(LEARNED_LAZYSP_POLICIES) <= set(graph_policies()) & set(POLICIES)
    lib = PathLibrary.from_sequences([[0, 1, 2]], 9)
    args = (lib, np.ones(9), np.full(9, 0.5), None, 0)
    bare = PolicyContext(*args, graph=DETOURS, start=0, goal=3)
    wrong = PolicyContext(*args, graph=DETOURS, start=0, goal=3, train_worlds=DETOUR_WORLDS[:, :5])
    full = PolicyContext(*args, graph=DETOURS, start=0, goal=3, train_worlds=DETOUR_WORLDS)
    for name in LEARNED_LAZYSP_POLICIES:
        with pytest.raises(ProblemError, match="training worlds"):
            POLICIES[name](bare)
        with pytest.raises(ProblemError, match="shape"):
            POLICIES[name](wrong)
        with pytest.raises(ProblemError, match="graph"):
            POLICIES[name](PolicyContext(*args, train_worlds=DETOUR_WORLDS))
        pol = POLICIES[name](full)
        assert pol.name == name
        assert isinstance(pol, GraphPathPolicy)
    # kappa is DEFAULT_PSEUDO_COUNT whatever the context's pseudo-count (direct_bisect's) says.
    for kappa in (None, TINY):
        ctx = PolicyContext(*args, pseudo_count=kappa, graph=DETOURS, start=0, goal=3, train_worlds=DETOUR_WORLDS)
        pol = POLICIES["lazysp_posterior"](ctx)
        assert isinstance(pol, PosteriorLazySP)
        pol.observe(7, False)  # leaves world A, where e1 is blocked
        assert pol.blocked_probability()[1] == pytest.approx(
            1 - DEFAULT_PSEUDO_COUNT * 0.5 / (1 + DEFAULT_PSEUDO_COUNT)
        )
    # The worlds' prior weights count: world A (e1 blocked) three times world B.
    weighted = PolicyContext(
        *args, graph=DETOURS, start=0, goal=3, train_worlds=DETOUR_WORLDS, train_weights=np.array([3.0, 1.0])
    )
    pol = POLICIES["lazysp_posterior"](weighted)
    assert isinstance(pol, PosteriorLazySP)
    assert pol.blocked_probability()[[0, 1]] == pytest.approx([0.25, 0.75])
    assert pol.select() == 1
    with pytest.raises(ProblemError, match="all 9 graph edges"):
        PosteriorLazySP(DETOURS, 0, 3, all_edge_outcomes(DETOUR_WORLDS[:, :4]), PosteriorSettings(1.0))


def test_observations_at_construction_count() -> None:
    pol = PosteriorLazySP(
        DETOURS,
        0,
        3,
        all_edge_outcomes(DETOUR_WORLDS),
        PosteriorSettings(TINY, delta=True),
        observations={7: False},
    )
    assert pol.num_consistent == 1
    assert pol.select() == 2


def test_dataset_episodes_find_the_shortest_feasible_path() -> None:
    problem = load_gccd_folder(gccd_folder("dataset_2d_1"))
    graph, worlds = problem.graph, problem.require_worlds()
    assert graph is not None
    assert problem.start is not None
    assert problem.goal is not None
    outcomes = all_edge_outcomes(worlds.X[worlds.train_ids])
    for delta in (False, True):
        for w in worlds.test_ids[:4]:
            x = worlds.X[w]
            pol = PosteriorLazySP(graph, problem.start, problem.goal, outcomes, PosteriorSettings(20.0, delta))
            result = run_episode(problem.library, problem.edge_costs, pol, TableOracle(x))
            edges = [c.edge for c in result.checks]
            assert len(set(edges)) == len(edges)
            assert result.status is PlanStatus.FOUND
            path = result.path_edges
            assert path is not None
            assert set(path.tolist()) <= set(edges)
            assert x[path].all()
            assert graph.lengths[path].sum() == pytest.approx(shortest_length(graph, x, problem.start, problem.goal))
