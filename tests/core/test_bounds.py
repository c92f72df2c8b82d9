"""Exact optima and lower bounds (drd_planner.core.bounds) on hand-worked and random tiny instances."""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence

import numpy as np
import numpy.typing as npt
import pytest

from drd_planner.core.bisect import Bisect
from drd_planner.core.bounds import (
    MAX_DRD_WORLDS,
    MAX_EPISODE_WORLDS,
    MAX_LIBRARY_EDGES,
    exact_bernoulli_optimum,
    exact_drd_optimum,
    exact_episode_optimum,
    expected_policy_cost_bernoulli,
    expected_policy_cost_database,
    oracle_lower_bound,
)
from drd_planner.core.direct import DirectSelector
from drd_planner.core.library import PathLibrary
from drd_planner.exceptions import PolicyError, ProblemError

TOL = 1e-9


# --------------------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------------------


def random_paths(rng: np.random.Generator, num_edges: int, num_paths: int, max_len: int) -> list[list[int]]:
    """``num_paths`` random paths of 1..max_len distinct edges out of ``num_edges``."""
    return [
        sorted(rng.choice(num_edges, size=int(rng.integers(1, min(max_len, num_edges) + 1)), replace=False))
        for _ in range(num_paths)
    ]


def all_worlds(num_edges: int) -> npt.NDArray[np.bool_]:
    """(2^E, E) every outcome vector."""
    return np.array(list(itertools.product([False, True], repeat=num_edges)), dtype=bool).reshape(
        -1, num_edges
    )


def bernoulli_prior(worlds: npt.NDArray[np.bool_], theta: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """Probability of each outcome vector under independent edges."""
    return np.asarray(np.prod(np.where(worlds, theta, 1.0 - theta), axis=1), dtype=np.float64)


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
# oracle lower bound
# --------------------------------------------------------------------------------------------------


def test_oracle_lower_bound_small_example() -> None:
    R = np.array([[1, 0, 1], [0, 0, 0], [0, 1, 1], [1, 1, 1]], dtype=bool)
    bound = oracle_lower_bound(R, [3.0, 1.0, 2.0])
    assert bound.shape == (4,)
    assert bound[0] == 2.0 and bound[2] == 1.0 and bound[3] == 1.0
    assert np.isnan(bound[1])


def test_oracle_lower_bound_rejects_bad_shapes() -> None:
    with pytest.raises(ProblemError):
        oracle_lower_bound(np.ones((2, 3), dtype=bool), [1.0, 2.0])
    with pytest.raises(ProblemError):
        oracle_lower_bound(np.ones(3, dtype=bool), [1.0, 2.0, 3.0])


# --------------------------------------------------------------------------------------------------
# Bernoulli (SBFE) optimum: hand-worked cases
# --------------------------------------------------------------------------------------------------


def test_bernoulli_one_path_two_edges() -> None:
    # Check a first: pay c_a, then c_b only if a is free. Best order: c_a + th_a c_b vs c_b + th_b c_a.
    theta = np.array([0.3, 0.6])
    assert exact_bernoulli_optimum([[0, 1]], theta, [1.0, 1.0]) == pytest.approx(1.3)
    costs = np.array([2.0, 1.0])
    expected = min(2.0 + 0.3 * 1.0, 1.0 + 0.6 * 2.0)
    assert exact_bernoulli_optimum([[0, 1]], theta, costs) == pytest.approx(expected)
    assert expected == pytest.approx(2.2)


def test_bernoulli_two_disjoint_single_edge_paths() -> None:
    # Check a first: c_a, then b only when a is blocked.
    theta = np.array([0.3, 0.6])
    costs = np.array([2.0, 1.0])
    expected = min(2.0 + 0.7 * 1.0, 1.0 + 0.4 * 2.0)
    assert exact_bernoulli_optimum([[0], [1]], theta, costs) == pytest.approx(expected)
    assert expected == pytest.approx(1.8)


def test_bernoulli_ignores_edges_off_the_library_and_certain_edges() -> None:
    theta = np.array([0.5, 1.0, 0.2])
    # Edge 2 is on no path; edge 1 is surely free but must still be verified.
    assert exact_bernoulli_optimum([[0, 1]], theta, [1.0, 1.0, 1.0]) == pytest.approx(1.0 + 0.5)
    # A surely-blocked edge: checking it ends the episode at once.
    assert exact_bernoulli_optimum([[0, 1]], [0.5, 0.0, 0.5], [1.0, 1.0, 1.0]) == pytest.approx(1.0)


def test_bernoulli_matches_episode_optimum_on_enumerated_worlds() -> None:
    """The independent-edge model is the database of all 2^E worlds with the product prior."""
    rng = np.random.default_rng(11)
    for _ in range(25):
        num_edges = int(rng.integers(1, 5))
        paths = random_paths(rng, num_edges, int(rng.integers(1, 4)), 3)
        theta = rng.uniform(0.05, 0.95, num_edges)
        costs = rng.uniform(0.5, 2.0, num_edges)
        worlds = all_worlds(num_edges)
        prior = bernoulli_prior(worlds, theta)
        opt = exact_bernoulli_optimum(paths, theta, costs)
        assert exact_episode_optimum(worlds, paths, costs, prior) == pytest.approx(opt, abs=TOL)


def test_bernoulli_sanity_bounds() -> None:
    """0 <= verification bound <= OPT <= cost of checking every library edge; OPT scales with cost."""
    rng = np.random.default_rng(12)
    for _ in range(30):
        num_edges = int(rng.integers(2, 8))
        paths = random_paths(rng, num_edges, int(rng.integers(1, 5)), 4)
        theta = rng.uniform(0.1, 0.9, num_edges)
        costs = rng.uniform(0.5, 2.0, num_edges)
        opt = exact_bernoulli_optimum(paths, theta, costs)
        library = PathLibrary.from_sequences(paths, num_edges)
        worlds = all_worlds(num_edges)
        bound = np.nan_to_num(oracle_lower_bound(library.valid_paths(worlds), library.path_costs(costs)))
        verification = float(bernoulli_prior(worlds, theta) @ bound)
        assert 0.0 <= verification <= opt + TOL
        assert opt <= costs[library.library_edges].sum() + TOL
        assert exact_bernoulli_optimum(paths, theta, 3.0 * costs) == pytest.approx(3.0 * opt)
        # A more expensive edge never makes the problem cheaper.
        dearer = costs.copy()
        dearer[int(rng.integers(num_edges))] += 1.0
        assert exact_bernoulli_optimum(paths, theta, dearer) >= opt - TOL


# --------------------------------------------------------------------------------------------------
# policy evaluation and BiSECt vs OPT
# --------------------------------------------------------------------------------------------------


def bisect_factory(
    library: PathLibrary,
    theta: npt.NDArray[np.float64],
    costs: npt.NDArray[np.float64],
    max_prob_region: bool,
) -> Callable[[dict[int, bool]], Bisect]:
    """Builds a BiSECt selector that has heard the given observations."""

    def make(obs: dict[int, bool]) -> Bisect:
        return Bisect(library, theta, costs, max_prob_region=max_prob_region, observations=obs)

    return make


def test_policy_cost_of_a_fixed_order_by_hand() -> None:
    class FixedOrder:
        def __init__(self, obs: dict[int, bool]) -> None:
            self._obs = obs

        def select(self) -> int | None:
            return next((e for e in (1, 0) if e not in self._obs), None)

    theta = np.array([0.3, 0.6])
    costs = np.array([2.0, 1.0])
    # One path {0, 1}, checking 1 then 0: 1 + 0.6 * 2.
    assert expected_policy_cost_bernoulli([[0, 1]], theta, costs, FixedOrder) == pytest.approx(2.2)
    # Two single-edge paths: 1 + 0.4 * 2.
    assert expected_policy_cost_bernoulli([[0], [1]], theta, costs, FixedOrder) == pytest.approx(1.8)


def test_policy_cost_rejects_a_repeated_edge() -> None:
    class Stubborn:
        def __init__(self, obs: dict[int, bool]) -> None:
            pass

        def select(self) -> int | None:
            return 0

    with pytest.raises(PolicyError):
        expected_policy_cost_bernoulli([[0, 1]], [0.5, 0.5], [1.0, 1.0], Stubborn)


def test_policy_cost_bernoulli_equals_database_enumeration() -> None:
    """Tree expansion and running BiSECt on every world, weighted by its probability, agree."""
    rng = np.random.default_rng(13)
    for _ in range(10):
        num_edges = int(rng.integers(2, 7))
        paths = random_paths(rng, num_edges, int(rng.integers(1, 4)), 3)
        theta = rng.uniform(0.1, 0.9, num_edges)
        costs = rng.uniform(0.5, 2.0, num_edges)
        library = PathLibrary.from_sequences(paths, num_edges)
        worlds = all_worlds(num_edges)
        for mpr in (True, False):

            def run_one(
                h: int,
                mpr: bool = mpr,
                library: PathLibrary = library,
                theta: npt.NDArray[np.float64] = theta,
                costs: npt.NDArray[np.float64] = costs,
                worlds: npt.NDArray[np.bool_] = worlds,
            ) -> float:
                policy = Bisect(library, theta, costs, max_prob_region=mpr)
                total = 0.0
                while (edge := policy.select()) is not None:
                    total += float(costs[edge])
                    policy.observe(edge, bool(worlds[h, edge]))
                return total

            tree = expected_policy_cost_bernoulli(
                paths, theta, costs, bisect_factory(library, theta, costs, mpr)
            )
            enumerated = expected_policy_cost_database(
                worlds, paths, costs, run_one, bernoulli_prior(worlds, theta)
            )
            assert tree == pytest.approx(enumerated, abs=TOL)


def test_bisect_never_beats_the_bernoulli_optimum() -> None:
    rng = np.random.default_rng(14)
    ratios: dict[bool, list[float]] = {True: [], False: []}
    for trial in range(200):
        num_edges = int(rng.integers(2, 11))  # <= 10 relevant edges
        paths = random_paths(rng, num_edges, int(rng.integers(1, 6)), 5)
        theta = rng.uniform(0.1, 0.9, num_edges)
        costs = np.ones(num_edges) if trial % 2 == 0 else rng.uniform(0.5, 2.0, num_edges)
        library = PathLibrary.from_sequences(paths, num_edges)
        opt = exact_bernoulli_optimum(paths, theta, costs)
        assert opt > 0
        for mpr in (True, False):
            cost = expected_policy_cost_bernoulli(
                paths, theta, costs, bisect_factory(library, theta, costs, mpr)
            )
            assert cost >= opt - TOL, (trial, mpr, cost, opt)
            ratios[mpr].append(cost / opt)
    for mpr, r in ratios.items():
        arr = np.array(r)
        print(
            f"BiSECt(max_prob_region={mpr}) / OPT over {arr.size} instances: "
            f"mean {arr.mean():.4f}, max {arr.max():.4f}, optimal in {np.mean(arr < 1 + 1e-9):.0%}"
        )


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
        library = PathLibrary.from_sequences(
            random_paths(rng, num_edges, int(rng.integers(2, 6)), 4), num_edges
        )
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
    never_called = bisect_factory(
        PathLibrary.from_sequences(paths, big), np.full(big, 0.5), np.ones(big), True
    )
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
