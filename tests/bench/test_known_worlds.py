"""The known-worlds bound (drd_planner.bench.known_worlds): exact on tiny instances, a partition bound."""

from __future__ import annotations

import numpy as np
import pytest
from optima_cases import TOL, random_paths

from drd_planner.bench.known_worlds import known_worlds_bound, known_worlds_optimum
from drd_planner.bench.optima import exact_episode_optimum
from drd_planner.core.bounds import oracle_lower_bound
from drd_planner.core.library import PathLibrary
from drd_planner.exceptions import ProblemError


def _feasible_instance(
    rng: np.random.Generator, num_edges: int, num_worlds: int, num_paths: int
) -> tuple[np.ndarray, list[list[int]]]:
    """Random worlds (each with a valid path) over a library that uses every edge."""
    paths = random_paths(rng, num_edges, num_paths, 3)
    used = sorted({int(e) for p in paths for e in p})
    local = {e: i for i, e in enumerate(used)}
    paths = [[local[int(e)] for e in p] for p in paths]
    library = PathLibrary.from_sequences(paths, len(used))
    draws = rng.random((50 * num_worlds, len(used))) < 0.6
    x = draws[library.valid_paths(draws).any(axis=1)][:num_worlds]
    assert x.shape[0] == num_worlds
    return x, paths


def test_two_worlds_with_disjoint_paths_pay_one_check_that_finds_out() -> None:
    # World 0: only path {0, 1} valid (edge 2 blocked); world 1: only path {2, 3} valid (edge 0 blocked).
    x = np.array([[1, 1, 0, 1], [0, 1, 1, 1]], dtype=bool)
    paths = [[0, 1], [2, 3]]
    # The first check (0 or 2) splits them; the world it blocks pays it on top of its own 2 checks.
    assert known_worlds_optimum(x, paths, np.ones(4)) == pytest.approx(2.5)
    assert oracle_lower_bound(PathLibrary.from_sequences(paths, 4).valid_paths(x), [2.0, 2.0]).mean() == 2.0


@pytest.mark.parametrize("seed", range(40))
def test_equals_the_exact_episode_optimum_when_every_edge_is_a_library_edge(seed: int) -> None:
    rng = np.random.default_rng(seed)
    x, paths = _feasible_instance(rng, int(rng.integers(3, 9)), int(rng.integers(1, 8)), int(rng.integers(1, 6)))
    costs = rng.integers(1, 4, size=x.shape[1]).astype(float) if seed % 2 else np.ones(x.shape[1])
    value = known_worlds_optimum(x, paths, costs)
    assert value == pytest.approx(exact_episode_optimum(x, paths, costs), abs=TOL)
    library = PathLibrary.from_sequences(paths, x.shape[1])
    assert value >= oracle_lower_bound(library.valid_paths(x), library.path_costs(costs)).mean() - TOL


def test_a_check_off_the_library_that_tells_the_worlds_apart_lowers_the_optimum() -> None:
    # Edge 4 is on no path and free only in world 0. Edges 0 and 2 cost 5: telling the worlds apart
    # with a library check wastes 5 in one of them (6 + 5 / 2); the probe costs 1 (1 + 6).
    x = np.array([[1, 1, 0, 1, 1], [0, 1, 1, 1, 0]], dtype=bool)
    paths = [[0, 1], [2, 3]]
    costs = np.array([5.0, 1.0, 5.0, 1.0, 1.0])
    with_probe = known_worlds_optimum(x, paths, costs)
    assert with_probe == pytest.approx(1.0 + 6.0)  # probe, then 5 + 1 on either path
    assert exact_episode_optimum(x, paths, costs) == pytest.approx(6.0 + 2.5)  # 6 + half of a wasted 5
    assert with_probe < exact_episode_optimum(x, paths, costs)


@pytest.mark.parametrize("seed", range(10))
def test_the_optimum_of_a_group_is_at_least_the_mean_of_its_halves(seed: int) -> None:
    rng = np.random.default_rng(100 + seed)
    x, paths = _feasible_instance(rng, 12, 10, 8)
    costs = np.ones(x.shape[1])
    half = x.shape[0] // 2
    whole = known_worlds_optimum(x, paths, costs)
    halves = (
        half * known_worlds_optimum(x[:half], paths, costs)
        + (x.shape[0] - half) * known_worlds_optimum(x[half:], paths, costs)
    ) / x.shape[0]
    assert whole >= halves - TOL


def test_the_bound_partitions_the_worlds_and_groups_of_one_give_the_oracle_bound() -> None:
    rng = np.random.default_rng(7)
    x, paths = _feasible_instance(rng, 14, 40, 10)
    costs = rng.integers(1, 3, size=x.shape[1]).astype(float)
    ids = np.arange(x.shape[0])
    library = PathLibrary.from_sequences(paths, x.shape[1])
    oracle = oracle_lower_bound(library.valid_paths(x), library.path_costs(costs)).mean()
    singles = known_worlds_bound(x, paths, costs, ids, group_size=1)
    assert singles.mean == pytest.approx(oracle)
    assert singles.oracle_mean == pytest.approx(oracle)
    grouped = known_worlds_bound(x, paths, costs, ids, group_size=6, seed=3)
    assert sorted(w for g in grouped.groups for w in g) == ids.tolist()
    assert grouped.sizes.max() <= 6
    assert grouped.sizes.max() - grouped.sizes.min() <= 1
    assert grouped.oracle_mean == pytest.approx(oracle)
    assert grouped.mean >= oracle - TOL
    assert np.all(grouped.optima >= grouped.oracle - TOL)
    again = known_worlds_bound(x, paths, costs, ids, group_size=6, seed=3)
    assert again.groups == grouped.groups
    assert np.array_equal(again.optima, grouped.optima)


def test_bad_input_is_refused_with_a_problem_error() -> None:
    x = np.array([[1, 1, 0, 1], [0, 1, 1, 1]], dtype=bool)
    paths = [[0, 1], [2, 3]]
    with pytest.raises(ProblemError, match="no valid library path"):
        known_worlds_optimum(np.array([[0, 1, 0, 1]], dtype=bool), paths, np.ones(4))
    with pytest.raises(ProblemError, match="budget of 1 nodes"):
        known_worlds_optimum(x, paths, np.ones(4), node_budget=1)
    with pytest.raises(ProblemError, match="group_size"):
        known_worlds_bound(x, paths, np.ones(4), [0, 1], group_size=0)
    with pytest.raises(ProblemError, match="world_ids"):
        known_worlds_bound(x, paths, np.ones(4), [0, 2], group_size=1)
    with pytest.raises(ProblemError, match="at least one world"):
        known_worlds_optimum(np.zeros((0, 4), dtype=bool), paths, np.ones(4))
    with pytest.raises(ProblemError, match="cost"):
        known_worlds_optimum(x, paths, np.zeros(4))
