"""Tests of the posterior leaf bias: hand-computed values, the Bisect re-bias and the policy."""

from __future__ import annotations

import numpy as np
import pytest

from drd_planner.core.bisect import Bisect
from drd_planner.core.episode import TableOracle, run_episode
from drd_planner.core.library import PathLibrary
from drd_planner.core.policies import DirectBisectPolicy
from drd_planner.core.posterior import ConsistentWorldsBias, TrainingOutcomes
from drd_planner.core.tree import build_tree
from drd_planner.data.planar_problem import make_planar_problem
from drd_planner.exceptions import ProblemError

# 4 training worlds over the library edges 1, 3, 4 of a 6-edge graph.
WORLDS = np.array(
    [
        [1, 1, 0],
        [1, 0, 1],
        [0, 1, 1],
        [1, 1, 1],
    ],
    dtype=bool,
)
LIB = np.array([1, 3, 4])


def test_bias_is_the_shrunk_free_fraction_of_the_consistent_worlds() -> None:
    bias = ConsistentWorldsBias(TrainingOutcomes(WORLDS, LIB, 6), pseudo_count=2.0, alpha=1.0)
    marginal = WORLDS.mean(axis=0)
    np.testing.assert_allclose(bias.theta()[LIB], marginal)  # all consistent: the marginal itself
    assert bias.theta()[[0, 2, 5]].tolist() == [0.5, 0.5, 0.5]
    bias.observe(1, True)  # drops world 2
    assert bias.num_consistent == 3
    # edge 3: free in 2 of the 3 consistent worlds; shrunk with 2 pseudo-worlds at the marginal 0.75.
    assert bias.theta()[3] == pytest.approx((2 + 2 * 0.75) / (3 + 2))
    bias.observe(4, False)  # drops worlds 1 and 3, leaves world 0
    assert bias.num_consistent == 1
    assert bias.theta()[3] == pytest.approx((1 + 2 * 0.75) / (1 + 2))
    bias.observe(3, False)  # contradicts world 0: nothing left, the marginal remains
    assert bias.num_consistent == 0
    np.testing.assert_allclose(bias.theta()[LIB], marginal)
    bias.observe(0, False)  # off the library: ignored
    assert bias.num_consistent == 0


def test_alpha_mixes_toward_one_half_and_weights_count() -> None:
    weights = np.array([3.0, 1.0, 0.0, 0.0])
    bias = ConsistentWorldsBias(TrainingOutcomes(WORLDS, LIB, 6, weights=weights), pseudo_count=1.0, alpha=0.9)
    # weights scaled to mean 1: 3, 1, 0, 0; edge 3 free in worlds 0 (w 3) and 2, 3 (w 0).
    marginal = 3.0 / 4.0
    assert bias.theta()[3] == pytest.approx(0.9 * (3.0 + 1.0 * marginal) / (4.0 + 1.0) + 0.05)


@pytest.mark.parametrize("kappa", [0.0, -1.0, float("inf"), float("nan")])
def test_bad_pseudo_count_is_refused(kappa: float) -> None:
    with pytest.raises(ProblemError, match="pseudo_count"):
        ConsistentWorldsBias(TrainingOutcomes(WORLDS, LIB, 6), pseudo_count=kappa)


def test_bad_shapes_and_weights_are_refused() -> None:
    with pytest.raises(ProblemError, match="world_free"):
        TrainingOutcomes(WORLDS[:, :2], LIB, 6)
    with pytest.raises(ProblemError, match="weights"):
        TrainingOutcomes(WORLDS, LIB, 6, weights=[1.0, -1.0, 1.0, 1.0])


def test_set_theta_equals_a_fresh_state_with_the_same_observations() -> None:
    library = PathLibrary((np.array([0, 1, 2]), np.array([0, 3]), np.array([4, 2, 5])), 6)
    rng = np.random.default_rng(0)
    theta_a, theta_b = rng.uniform(0.2, 0.9, 6), rng.uniform(0.2, 0.9, 6)
    costs = np.ones(6)
    observations = {0: True, 4: False}
    moved = Bisect(library, theta_a, costs, observations=observations)
    moved.set_theta(theta_b)
    fresh = Bisect(library, theta_b, costs, observations=observations)
    np.testing.assert_allclose(moved.log_path_probability, fresh.log_path_probability)
    assert moved.select() == fresh.select()
    with pytest.raises(ProblemError, match="theta"):
        moved.set_theta(np.full(5, 0.5))


@pytest.fixture(scope="module")
def planar():  # type: ignore[no-untyped-def]
    problem = make_planar_problem(num_vertices=60, model="one_wall", num_worlds=150, max_paths=40, seed=4)
    return problem, build_tree(problem, progress=False)


def test_posterior_leaf_is_deterministic_and_finds_valid_paths(planar) -> None:  # type: ignore[no-untyped-def]
    problem, tree = planar
    worlds = problem.require_worlds()
    for world in worlds.test_ids[worlds.R[worlds.test_ids].any(axis=1)][:15]:
        runs = []
        for _ in range(2):
            policy = DirectBisectPolicy(tree, problem.library, problem.edge_costs, eta=0.3, pseudo_count=10.0)
            result = run_episode(problem.library, problem.edge_costs, policy, TableOracle(worlds.X[world]))
            runs.append([(c.edge, c.free) for c in result.checks])
            assert result.success
            assert worlds.R[world, result.path_index]
        assert runs[0] == runs[1]


def test_posterior_leaf_bias_follows_the_consistent_worlds(planar) -> None:  # type: ignore[no-untyped-def]
    problem, tree = planar
    worlds = problem.require_worlds()
    world = int(worlds.test_ids[0])
    policy = DirectBisectPolicy(tree, problem.library, problem.edge_costs, eta=1.0, pseudo_count=4.0)
    assert policy.stage == "bisect"
    assert policy.pseudo_count == 4.0
    edge = policy.select()
    assert edge is not None
    free = bool(worlds.X[world, edge])
    policy.observe(edge, free)
    train = worlds.train_ids
    lib = tree.library_edges
    kept = train[worlds.X[train, edge] == free]
    expected = (
        0.99 * (worlds.X[np.ix_(kept, lib)].sum(0) + 4.0 * worlds.X[np.ix_(train, lib)].mean(0)) / (kept.size + 4.0)
        + 0.005
    )
    # The policy's BiSECt now ranks paths with the re-conditioned bias: compare with a fresh state.
    theta = np.full(problem.num_edges, 0.5)
    theta[lib] = expected
    fresh = Bisect(problem.library, theta, problem.edge_costs, observations={edge: free})
    assert policy.select() == fresh.select()


@pytest.mark.parametrize(("seed", "weighted"), [(0, False), (1, False), (2, True)])
def test_updates_per_outcome_equal_the_bias_of_the_consistent_worlds(seed: int, weighted: bool) -> None:
    rng = np.random.default_rng(seed)
    worlds = rng.random((150, 40)) < 0.7
    lib = np.sort(rng.choice(50, size=40, replace=False))
    weights = rng.uniform(0.0, 2.0, 150) if weighted else None
    outcomes = TrainingOutcomes(worlds, lib, 50, weights=weights)
    w = outcomes.weights
    # The first episode on the outcomes keeps rows, the later ones packed columns (uniform weights).
    for _episode in range(3):
        bias = ConsistentWorldsBias(outcomes, pseudo_count=5.0, alpha=0.99)
        consistent = np.ones(150, dtype=bool)
        truth = worlds[int(rng.integers(150))]
        for edge in rng.permutation(50)[:25].tolist():
            col = int(np.searchsorted(lib, edge))
            on_library = col < lib.size and lib[col] == edge
            free = bool(truth[col]) if on_library and rng.random() < 0.9 else bool(rng.random() < 0.5)
            bias.observe(edge, free)
            if on_library:
                consistent &= worlds[:, col] == free
            mass = w[consistent].sum()
            data = (w[consistent] @ worlds[consistent] + 5.0 * outcomes.marginal) / (mass + 5.0)
            expected = np.full(50, 0.5)
            expected[lib] = 0.99 * np.clip(data, 0.0, 1.0) + 0.005
            assert bias.num_consistent == int(consistent.sum())
            np.testing.assert_allclose(bias.theta(), expected, rtol=1e-12, atol=0.0)
            np.testing.assert_array_equal(bias.library_theta(), bias.theta()[lib])


def _random_case(
    rng: np.random.Generator,
) -> tuple[tuple[np.ndarray, ...], PathLibrary, np.ndarray, np.ndarray, np.ndarray]:
    """25 random paths over 40 edges: (paths, library, (E,) costs, the library's edges, (E,) theta)."""
    num_edges = 40
    paths = tuple(rng.choice(num_edges - 4, size=int(rng.integers(2, 9)), replace=False) for _ in range(25))
    library = PathLibrary(paths, num_edges)
    costs = rng.uniform(0.5, 2.0, num_edges)
    return paths, library, costs, library.library_edges, rng.uniform(0.2, 0.95, num_edges)


@pytest.mark.parametrize("seed", range(4))
def test_outcomes_and_new_biases_keep_log_p_as_a_fresh_state_sums_it(seed: int) -> None:
    rng = np.random.default_rng(seed)
    paths, library, costs, lib, theta = _random_case(rng)
    moved = Bisect(library, theta, costs, region_rule="per_check")
    observations: dict[int, bool] = {}
    for edge in rng.permutation(lib)[:12].tolist():
        if moved.solved():
            break
        moved.select()  # builds and keeps the proof order
        free = bool(rng.random() < 0.7)
        moved.observe(edge, free)
        observations[edge] = free
        if rng.random() < 0.7:  # a new bias for the library edges (the posterior leaf)
            theta[lib] = np.where(rng.random(lib.size) < 0.8, rng.uniform(0.2, 0.95, lib.size), theta[lib])
            moved.set_theta(theta[lib], edges=lib)
        fresh = Bisect(library, theta, costs, observations=observations, region_rule="per_check")
        fresh.set_theta(theta)
        moved.set_theta(theta)
        alive = fresh.alive
        assert moved.alive.tolist() == alive.tolist()
        assert moved.log_path_probability.tolist() == fresh.log_path_probability.tolist()
        log_theta = np.log(np.clip(theta, 1e-9, 1 - 1e-9))
        for i in np.flatnonzero(alive).tolist():
            untested = [e for e in paths[i].tolist() if e not in observations]
            assert moved.log_path_probability[i] == pytest.approx(log_theta[untested].sum(), abs=1e-12)
        if not fresh.solved():
            assert moved.select() == fresh.select()


@pytest.mark.parametrize("seed", range(4))
def test_the_library_bias_path_equals_set_theta_bit_for_bit(seed: int) -> None:
    """``set_library_theta`` (the posterior leaf's path; None: unchanged) keeps what ``set_theta`` keeps."""
    rng = np.random.default_rng(40 + seed)
    _, library, costs, lib, theta = _random_case(rng)
    by_library = Bisect(library, theta, costs, region_rule="per_check")
    by_edges = Bisect(library, theta, costs, region_rule="per_check")
    assert by_library.library_edges.tolist() == lib.tolist()
    for edge in rng.permutation(lib)[:12].tolist():
        if by_edges.solved():
            break
        assert by_library.select() == by_edges.select()
        free = bool(rng.random() < 0.7)
        by_library.observe(edge, free)
        by_edges.observe(edge, free)
        if rng.random() < 0.6:  # a new bias for the library edges, some values at the ends of [0, 1]
            theta[lib] = np.where(rng.random(lib.size) < 0.8, rng.uniform(0.0, 1.0, lib.size), theta[lib])
            theta[lib[:2]] = [0.0, 1.0]
            by_library.set_library_theta(theta[lib].copy())
        else:
            by_library.set_library_theta(None)
        by_edges.set_theta(theta[lib], edges=lib)
        assert by_library.log_path_probability.tolist() == by_edges.log_path_probability.tolist()
        if not by_edges.solved():
            cand = by_edges.alive_candidates()
            assert by_library.gains(cand).tolist() == by_edges.gains(cand).tolist()
