"""Exact optima on a finite database (drd_planner.bench.optima) on hand-worked and random tiny instances."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
import pytest
from optima_cases import TOL, bisect_factory, random_paths

from drd_planner.bench.optima import exact_drd_optimum, exact_episode_optimum, expected_policy_cost_database
from drd_planner.bench.optima_bernoulli import exact_bernoulli_optimum, expected_policy_cost_bernoulli
from drd_planner.bench.optima_support import MAX_DRD_WORLDS, MAX_EPISODE_WORLDS, MAX_LIBRARY_EDGES
from drd_planner.core.bounds import oracle_lower_bound
from drd_planner.core.direct import DirectSelector
from drd_planner.core.library import PathLibrary
from drd_planner.exceptions import ProblemError

# --------------------------------------------------------------------------------------------------
# reference helpers
# --------------------------------------------------------------------------------------------------


def direct_decision_cost(
    selector: DirectSelector, X: npt.NDArray[np.bool_], costs: npt.NDArray[np.float64], world: int
) -> float:
    """Cost the greedy DiRECt decision policy pays on ``world`` (all worlds active at the start)."""
    active = np.arange(X.shape[0])
    total = 0.0
    for _ in range(X.shape[1] + 1):
        choice = selector.select(active)
        if choice is None:
            return total
        total += float(costs[choice.edge])
        active = active[X[active, choice.edge] == X[world, choice.edge]]
    raise AssertionError("DiRECt did not stop")


def naive_drd(
    X: npt.NDArray[np.bool_],
    R: npt.NDArray[np.bool_],
    costs: npt.NDArray[np.float64],
    prior: npt.NDArray[np.float64],
) -> float:
    """Plain recursion over version spaces as index tuples (no memo, no pruning): the reference."""

    def value(h: tuple[int, ...]) -> float:
        rows = R[list(h)]
        if not rows.any() or rows.all(axis=0).any():
            return 0.0
        best = math.inf
        p = prior[list(h)].sum()
        for t in range(X.shape[1]):
            h1 = tuple(i for i in h if X[i, t])
            h0 = tuple(i for i in h if not X[i, t])
            if h1 and h0:
                v = costs[t] + (prior[list(h1)].sum() * value(h1) + prior[list(h0)].sum() * value(h0)) / p
                best = min(best, v)
        return 0.0 if best == math.inf else best

    return value(tuple(range(X.shape[0])))


def naive_episode(
    X: npt.NDArray[np.bool_],
    paths: Sequence[Sequence[int]],
    costs: npt.NDArray[np.float64],
    prior: npt.NDArray[np.float64],
) -> float:
    """Plain recursion over (observations, version space), no memo, no pruning: the reference."""

    def value(obs: dict[int, bool], h: tuple[int, ...]) -> float:
        alive = [p for p in paths if all(obs.get(e, True) for e in p)]
        if not alive or any(all(e in obs for e in p) for p in alive):
            return 0.0
        p_h = prior[list(h)].sum()
        best = math.inf
        for e in sorted({e for p in alive for e in p if e not in obs}):
            v = float(costs[e])
            for outcome in (False, True):
                sub = tuple(i for i in h if X[i, e] == outcome)
                if sub:
                    v += prior[list(sub)].sum() / p_h * value({**obs, e: outcome}, sub)
            best = min(best, v)
        return best

    return value({}, tuple(range(X.shape[0])))


# --------------------------------------------------------------------------------------------------
# finite-database DRD optimum
# --------------------------------------------------------------------------------------------------


def one_test_database() -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]]:
    """Worlds 0, 1 in region A, worlds 2, 3 in region B; test 0 decides; tests 1, 2 only help."""
    X = np.array([[1, 1, 1], [1, 0, 0], [0, 1, 0], [0, 0, 0]], dtype=bool)
    R = np.array([[1, 0], [1, 0], [0, 1], [0, 1]], dtype=bool)
    return X, R


def test_drd_one_test_decides() -> None:
    X, R = one_test_database()
    assert exact_drd_optimum(X, R, [1.0, 1.0, 1.0]) == pytest.approx(1.0)
    assert exact_drd_optimum(X, R, [1.0, 3.0, 3.0]) == pytest.approx(1.0)


def test_drd_cheap_tests_beat_the_deciding_test() -> None:
    # c = (5, 1, 1). Test 1 first splits {0, 2} | {1, 3}; {0, 2} then needs test 2 (cost 1) and
    # {1, 3} needs test 0 (cost 5): 1 + 0.5 * 1 + 0.5 * 5 = 4. Test 2 first gives 4.25, test 0 gives 5.
    X, R = one_test_database()
    assert exact_drd_optimum(X, R, [5.0, 1.0, 1.0]) == pytest.approx(4.0)
    # Prior (0.4, 0.1, 0.4, 0.1): test 1 first now gives 1 + 0.8 * 1 + 0.2 * 5 = 2.8, but test 2
    # first is better: {0} | {1, 2, 3}, then test 1 splits {2} | {1, 3} and only {1, 3} (mass 0.2)
    # needs test 0: 1 + 0.6 * (1 + (0.2 / 0.6) * 5) = 2.6.
    prior = np.array([0.4, 0.1, 0.4, 0.1])
    assert exact_drd_optimum(X, R, [5.0, 1.0, 1.0], prior) == pytest.approx(2.6)


def test_drd_zero_when_decided() -> None:
    X = np.array([[1, 0], [0, 1], [1, 1]], dtype=bool)
    # A common region (path 1 valid everywhere).
    assert exact_drd_optimum(X, np.array([[1, 1], [0, 1], [0, 1]], dtype=bool), [1.0, 1.0]) == 0.0
    # No region at all.
    assert exact_drd_optimum(X, np.zeros((3, 2), dtype=bool), [1.0, 1.0]) == 0.0
    # Only one world.
    assert exact_drd_optimum(X[:1], np.array([[1, 0]], dtype=bool), [1.0, 1.0]) == 0.0


def test_drd_matches_naive_reference() -> None:
    rng = np.random.default_rng(21)
    for _ in range(40):
        n = int(rng.integers(1, 7))
        num_edges = int(rng.integers(1, 5))
        X = rng.random((n, num_edges)) < 0.6
        R = rng.random((n, int(rng.integers(1, 4)))) < 0.4
        costs = rng.uniform(0.5, 2.0, num_edges)
        prior = rng.uniform(0.1, 1.0, n)
        assert exact_drd_optimum(X, R, costs, prior) == pytest.approx(naive_drd(X, R, costs, prior), abs=TOL)


def test_drd_prior_duplicates_and_monotonicity() -> None:
    rng = np.random.default_rng(22)
    for _ in range(30):
        n = int(rng.integers(2, 10))
        num_edges = int(rng.integers(2, 7))
        X = rng.random((n, num_edges)) < 0.6
        library = PathLibrary.from_sequences(random_paths(rng, num_edges, 3, 3), num_edges)
        R = library.valid_paths(X)
        costs = rng.uniform(0.5, 2.0, num_edges)
        opt = exact_drd_optimum(X, R, costs)
        assert opt >= 0.0
        # Duplicating world 0 is the same as doubling its prior weight.
        dup = exact_drd_optimum(np.vstack([X, X[:1]]), np.vstack([R, R[:1]]), costs)
        weights = np.ones(n)
        weights[0] = 2.0
        assert dup == pytest.approx(exact_drd_optimum(X, R, costs, weights), abs=TOL)
        # Zero prior weight removes a world.
        zero = np.ones(n)
        zero[-1] = 0.0
        assert exact_drd_optimum(X, R, costs, zero) == pytest.approx(exact_drd_optimum(X[:-1], R[:-1], costs))
        # An extra test never hurts; a dearer test never helps; costs scale the optimum.
        extra = np.hstack([X, rng.random((n, 1)) < 0.5])
        assert exact_drd_optimum(extra, R, np.append(costs, 0.7)) <= opt + TOL
        assert exact_drd_optimum(X, R, costs + 0.5) >= opt - TOL
        assert exact_drd_optimum(X, R, 2.0 * costs) == pytest.approx(2.0 * opt)


def test_drd_optimum_below_direct_greedy() -> None:
    rng = np.random.default_rng(23)
    ratios = []
    for trial in range(60):
        n = int(rng.integers(4, 15))
        num_edges = int(rng.integers(4, 11))
        X = rng.random((n, num_edges)) < rng.uniform(0.4, 0.85)
        library = PathLibrary.from_sequences(random_paths(rng, num_edges, int(rng.integers(2, 6)), 4), num_edges)
        R = library.valid_paths(X)
        costs = np.ones(num_edges) if trial % 3 else rng.uniform(0.5, 2.0, num_edges)
        prior = None if trial % 4 else rng.uniform(0.2, 1.0, n)
        selector = DirectSelector(X, R, costs, prior=prior)

        def run_one(
            h: int,
            selector: DirectSelector = selector,
            X: npt.NDArray[np.bool_] = X,
            costs: npt.NDArray[np.float64] = costs,
        ) -> float:
            return direct_decision_cost(selector, X, costs, h)

        greedy = expected_policy_cost_database(X, library.path_edges, costs, run_one, prior)
        opt = exact_drd_optimum(X, R, costs, prior)
        assert opt <= greedy + TOL, (trial, opt, greedy)
        if opt > 0:
            ratios.append(greedy / opt)
        else:
            assert greedy == 0.0
    arr = np.array(ratios)
    print(
        f"DiRECt greedy / DRD OPT over {arr.size} databases with OPT > 0: "
        f"mean {arr.mean():.4f}, max {arr.max():.4f}, optimal in {np.mean(arr < 1 + 1e-9):.0%}"
    )


def test_drd_refuses_large_or_inconsistent_input() -> None:
    n = MAX_DRD_WORLDS + 1
    with pytest.raises(ProblemError, match="worlds"):
        exact_drd_optimum(np.zeros((n, 2), dtype=bool), np.zeros((n, 1), dtype=bool), [1.0, 1.0])
    with pytest.raises(ProblemError):
        exact_drd_optimum(np.zeros((3, 2), dtype=bool), np.zeros((2, 1), dtype=bool), [1.0, 1.0])
    with pytest.raises(ProblemError):
        exact_drd_optimum(np.zeros((3, 2), dtype=bool), np.zeros((3, 1), dtype=bool), [1.0, 0.0])
    with pytest.raises(ProblemError):
        exact_drd_optimum(np.zeros((3, 2), dtype=bool), np.zeros((3, 1), dtype=bool), [1.0, 1.0], [1, -1, 1])
    with pytest.raises(ProblemError):
        exact_drd_optimum(np.full((3, 2), 2), np.zeros((3, 1), dtype=bool), [1.0, 1.0])


# --------------------------------------------------------------------------------------------------
# episode optimum on a database
# --------------------------------------------------------------------------------------------------


def test_episode_hand_cases() -> None:
    # One world, one free path of two edges: it must be verified, although nothing is uncertain.
    X = np.array([[1, 1, 0]], dtype=bool)
    assert exact_episode_optimum(X, [[0, 1]], [1.0, 2.0, 1.0]) == pytest.approx(3.0)
    assert exact_drd_optimum(X, np.array([[1]], dtype=bool), [1.0, 2.0, 1.0]) == 0.0
    # Two worlds, paths {0} and {1}; world 0: edge 0 free, world 1: only edge 1 free.
    # Check 0 first: 1 + 0.5 * 1 = 1.5 (check 1 first is the same by symmetry).
    X = np.array([[1, 0], [0, 1]], dtype=bool)
    assert exact_episode_optimum(X, [[0], [1]], [1.0, 1.0]) == pytest.approx(1.5)
    # With prior (0.9, 0.1) checking edge 0 first is best: 1 + 0.1.
    assert exact_episode_optimum(X, [[0], [1]], [1.0, 1.0], [0.9, 0.1]) == pytest.approx(1.1)
    # No valid path in the only world: one blocked edge per path refutes them (shared edge 0).
    X = np.array([[0, 1, 1]], dtype=bool)
    assert exact_episode_optimum(X, [[0, 1], [0, 2]], [1.0, 1.0, 1.0]) == pytest.approx(1.0)


def test_episode_matches_naive_reference() -> None:
    rng = np.random.default_rng(31)
    for _ in range(150):
        n = int(rng.integers(1, 8))
        num_edges = int(rng.integers(2, 6))
        X = rng.random((n, num_edges)) < 0.6
        paths = random_paths(rng, num_edges, int(rng.integers(2, 5)), 3)
        costs = rng.uniform(0.5, 2.0, num_edges)
        prior = rng.uniform(0.1, 1.0, n)
        assert exact_episode_optimum(X, paths, costs, prior) == pytest.approx(
            naive_episode(X, paths, costs, prior), abs=TOL
        )


def test_episode_above_oracle_bound_and_drd_optimum() -> None:
    rng = np.random.default_rng(32)
    for _ in range(40):
        n = int(rng.integers(2, MAX_EPISODE_WORLDS + 1))
        num_edges = int(rng.integers(3, 11))
        X = rng.random((n, num_edges)) < rng.uniform(0.5, 0.9)
        paths = random_paths(rng, num_edges, int(rng.integers(1, 5)), 4)
        library = PathLibrary.from_sequences(paths, num_edges)
        costs = rng.uniform(0.5, 2.0, num_edges)
        prior = rng.uniform(0.1, 1.0, n)
        R = library.valid_paths(X)
        episode = exact_episode_optimum(X, paths, costs, prior)
        bound = np.nan_to_num(oracle_lower_bound(R, library.path_costs(costs)))
        assert episode >= float(prior @ bound / prior.sum()) - TOL
        assert episode >= exact_drd_optimum(X, R, costs, prior) - TOL
        assert episode <= costs[library.library_edges].sum() + TOL


def test_episode_and_bernoulli_refuse_large_instances() -> None:
    with pytest.raises(ProblemError, match="worlds"):
        exact_episode_optimum(np.ones((MAX_EPISODE_WORLDS + 1, 2), dtype=bool), [[0, 1]], [1.0, 1.0])
    big = MAX_LIBRARY_EDGES + 1
    paths = [[e] for e in range(big)]
    with pytest.raises(ProblemError, match="edges"):
        exact_episode_optimum(np.ones((2, big), dtype=bool), paths, np.ones(big))
    with pytest.raises(ProblemError, match="edges"):
        exact_bernoulli_optimum(paths, np.full(big, 0.5), np.ones(big))
    never_called = bisect_factory(PathLibrary.from_sequences(paths, big), np.full(big, 0.5), np.ones(big), True)
    with pytest.raises(ProblemError, match="edges"):
        expected_policy_cost_bernoulli(paths, np.full(big, 0.5), np.ones(big), never_called)
    with pytest.raises(ProblemError):
        exact_bernoulli_optimum([[0, 3]], [0.5, 0.5], [1.0, 1.0])  # edge outside the graph
    with pytest.raises(ProblemError):
        exact_bernoulli_optimum([[0, 1]], [0.5, 1.5], [1.0, 1.0])  # not a probability


def test_database_policy_cost_is_a_weighted_mean() -> None:
    X = np.ones((3, 2), dtype=bool)
    costs = [1.0, 1.0]
    assert expected_policy_cost_database(X, [[0, 1]], costs, lambda h: h) == pytest.approx(1.0)
    weighted = expected_policy_cost_database(X, [[0, 1]], costs, lambda h: h, [1.0, 0.0, 3.0])
    assert weighted == pytest.approx(1.5)
    with pytest.raises(ProblemError):
        expected_policy_cost_database(X, [[0, 1]], costs, lambda h: -1.0)
