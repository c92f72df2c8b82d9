"""Exact optima under independent edges (drd_planner.bench.optima_bernoulli) on tiny instances."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import pytest
from optima_cases import TOL, all_worlds, bernoulli_prior, bisect_factory, random_paths

from drd_planner.bench.optima import exact_episode_optimum, expected_policy_cost_database
from drd_planner.bench.optima_bernoulli import exact_bernoulli_optimum, expected_policy_cost_bernoulli
from drd_planner.core.bisect import Bisect
from drd_planner.core.bounds import oracle_lower_bound
from drd_planner.core.library import PathLibrary
from drd_planner.exceptions import PolicyError

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

            tree = expected_policy_cost_bernoulli(paths, theta, costs, bisect_factory(library, theta, costs, mpr))
            enumerated = expected_policy_cost_database(worlds, paths, costs, run_one, bernoulli_prior(worlds, theta))
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
            cost = expected_policy_cost_bernoulli(paths, theta, costs, bisect_factory(library, theta, costs, mpr))
            assert cost >= opt - TOL, (trial, mpr, cost, opt)
            ratios[mpr].append(cost / opt)
    for mpr, r in ratios.items():
        arr = np.array(r)
        print(
            f"BiSECt(max_prob_region={mpr}) / OPT over {arr.size} instances: "
            f"mean {arr.mean():.4f}, max {arr.max():.4f}, optimal in {np.mean(arr < 1 + 1e-9):.0%}"
        )
