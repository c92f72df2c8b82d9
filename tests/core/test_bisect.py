"""BiSECt: the closed-form gain against an explicit computation, and the authors' stored results."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from conftest import gccd_folder, libm_numpy

from drd_planner.core.bisect import Bisect, bias_from_worlds
from drd_planner.core.episode import TableOracle, run_episode
from drd_planner.core.library import PathLibrary
from drd_planner.core.policies import BisectPolicy
from drd_planner.data.bern_sets import load_bernoulli_test_set, load_stored_costs


def path_weight(path: list[int], theta: np.ndarray, obs: dict[int, bool]) -> float:
    """w_i(x_A) = [prod_{e in path, observed} P(x_e)]^2 (1 - p_i(x_A)) exactly as section 2.2 states."""
    seen = 1.0
    p = 1.0
    for e in path:
        if e in obs:
            seen *= theta[e] if obs[e] else 1.0 - theta[e]
            p *= 1.0 if obs[e] else 0.0
        else:
            p *= theta[e]
    return seen**2 * (1.0 - p)


def explicit_gain(paths: list[list[int]], theta: np.ndarray, obs: dict[int, bool], e: int) -> float:
    """1 - E_x[prod_i w_i(x_A, x_e) / w_i(x_A)] over the paths alive now (dead ones are pruned)."""
    alive = [p for p in paths if not any(obs.get(x) is False for x in p)]

    def ratio(outcome: bool) -> float:
        after = {**obs, e: outcome}
        return float(np.prod([path_weight(p, theta, after) / path_weight(p, theta, obs) for p in alive]))

    return 1.0 - (theta[e] * ratio(True) + (1.0 - theta[e]) * ratio(False))


@pytest.mark.parametrize("seed", range(60))
def test_closed_form_gain_matches_explicit_expectation(seed: int) -> None:
    rng = np.random.default_rng(seed)
    num_edges = int(rng.integers(3, 9))
    paths = [
        sorted(rng.choice(num_edges, size=int(rng.integers(1, min(5, num_edges + 1))), replace=False).tolist())
        for _ in range(int(rng.integers(1, 5)))
    ]
    theta = rng.uniform(0.1, 0.9, num_edges)
    library = PathLibrary.from_sequences(paths, num_edges)
    # observe a few free edges that do not complete a path, and maybe a blocked one
    obs: dict[int, bool] = {}
    for e in rng.permutation(num_edges)[: int(rng.integers(0, 3))].tolist():
        trial = {**obs, e: bool(rng.random() < 0.7)}
        alive_paths = [p for p in paths if not any(trial.get(x) is False for x in p)]
        if alive_paths and not any(all(trial.get(x) is True for x in p) for p in alive_paths):
            obs = trial
    bis = Bisect(library, theta, np.ones(num_edges), max_prob_region=False, observations=obs)
    assert not bis.solved()
    cand = np.array(
        sorted({e for p in paths if not any(obs.get(x) is False for x in p) for e in p if e not in obs}),
        dtype=np.int64,
    )
    got = bis.gains(cand)
    want = np.array([explicit_gain(paths, theta, obs, int(e)) for e in cand])
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(bis.scalar_gains(cand), want, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("seed", range(20))
def test_gains_in_python_floats_equal_the_vectorised_gains(seed: int) -> None:
    """Bit for bit where numpy's float64 exp/log family is the C library's (``libm_numpy``)."""
    rng = np.random.default_rng(500 + seed)
    num_edges = 12
    paths = [sorted(rng.choice(num_edges, size=int(rng.integers(1, 6)), replace=False).tolist()) for _ in range(6)]
    library = PathLibrary.from_sequences(paths, num_edges)
    theta = rng.uniform(0.02, 0.999, num_edges)  # p_i above 1/2 too: both forms of log(1 - e^x)
    bis = Bisect(library, theta, rng.uniform(0.5, 2.0, num_edges), max_prob_region=False)
    for edge in rng.permutation(num_edges)[:3].tolist():
        if bis.solved():
            break
        cand = bis.alive_candidates()
        vector, scalar = bis.gains(cand), np.array(bis.scalar_gains(cand))
        if libm_numpy():
            assert scalar.tolist() == vector.tolist()
        else:
            np.testing.assert_allclose(scalar, vector, rtol=1e-12)
        bis.observe(edge, bool(rng.random() < 0.8))


def test_observations_in_constructor_equal_observing_later() -> None:
    rng = np.random.default_rng(7)
    paths = [[0, 1, 2], [2, 3], [4, 5, 1]]
    theta = rng.uniform(0.2, 0.8, 6)
    lib = PathLibrary.from_sequences(paths, 6)
    a = Bisect(lib, theta, np.ones(6), observations={1: True, 3: False})
    b = Bisect(lib, theta, np.ones(6))
    b.observe(1, True)
    b.observe(3, False)
    np.testing.assert_array_equal(a.log_path_probability, b.log_path_probability)
    assert a.select() == b.select()
    assert not a.alive[1]


def test_dead_paths_do_not_attract_checks() -> None:
    # Path 0 is dead after edge 0 is blocked; its other edge 1 must never be chosen.
    lib = PathLibrary.from_sequences([[0, 1], [2, 3]], 4)
    bis = Bisect(lib, np.full(4, 0.5), np.ones(4), max_prob_region=False, observations={0: False})
    seen = set()
    while (e := bis.select()) is not None:
        seen.add(e)
        bis.observe(e, True)
    assert seen == {2, 3}


def test_bias_from_worlds_mixing_and_empty() -> None:
    X = np.array([[1, 0, 1], [1, 0, 0]], dtype=bool)
    np.testing.assert_allclose(bias_from_worlds(X, alpha=0.99), [0.995, 0.005, 0.5])
    np.testing.assert_allclose(bias_from_worlds(X, np.array([3.0, 1.0]), alpha=1.0), [1.0, 0.0, 0.75])
    np.testing.assert_allclose(bias_from_worlds(np.zeros((0, 3), dtype=bool)), [0.5, 0.5, 0.5])


def _policy_costs(set_path, max_prob_region: bool, lite: bool = False) -> np.ndarray:
    ts = load_bernoulli_test_set(set_path)

    class LitePolicy(BisectPolicy):
        def __init__(self) -> None:
            super().__init__(ts.library, ts.theta, ts.costs, max_prob_region=max_prob_region)
            self._bisect = Bisect(ts.library, ts.theta, ts.costs, max_prob_region=max_prob_region, lite=lite)

    costs = []
    for row in ts.outcomes:
        result = run_episode(ts.library, ts.costs, LitePolicy(), TableOracle(row))
        costs.append(result.total_cost(ts.costs))
    return np.array(costs)


@pytest.mark.parametrize(
    ("results_file", "row", "max_prob_region", "lite", "mean"),
    [
        ("test_set2.mat", 8, True, False, 12.85),  # direct_drd_bern_max_prob
        ("test_set2_drd.mat", 0, False, False, 39.50),  # direct_drd_bern, option 0
        ("test_set2_bernlite.mat", 0, False, True, 38.36),  # BiSECt-lite unrestricted
        ("test_set2_bernlite.mat", 1, True, True, 12.75),  # BiSECt-lite + MaxProbReg
    ],
)
def test_reproduces_authors_stored_costs_on_every_problem(
    results_file: str, row: int, max_prob_region: bool, lite: bool, mean: float
) -> None:
    folder = gccd_folder("dataset_bern_test_1")
    stored = load_stored_costs(folder / "results" / results_file)[row]
    ours = _policy_costs(folder / "test_set2.mat", max_prob_region, lite)
    assert ours.shape == (100,)
    np.testing.assert_array_equal(ours, stored)
    assert ours.mean() == pytest.approx(mean)


def test_stored_results_differ_between_variants() -> None:
    """Sanity: the two stored variants are different, so matching both is a real check."""
    folder = gccd_folder("dataset_bern_test_1")
    a = load_stored_costs(folder / "results" / "test_set2.mat")[8]
    b = load_stored_costs(folder / "results" / "test_set2_drd.mat")[0]
    assert (a != b).sum() > 50


def test_exhaustive_tiny_instance_reaches_every_outcome() -> None:
    """On every world of a tiny library, BiSECt ends with a verified path or proof of none."""
    paths = [[0, 1], [1, 2], [3]]
    lib = PathLibrary.from_sequences(paths, 4)
    theta = np.array([0.6, 0.7, 0.4, 0.3])
    for bits in itertools.product([False, True], repeat=4):
        for mpr in (True, False):
            result = run_episode(
                lib, np.ones(4), BisectPolicy(lib, theta, np.ones(4), max_prob_region=mpr), TableOracle(bits)
            )
            feasible = any(all(bits[e] for e in p) for p in paths)
            assert result.success == feasible


def test_bias_from_worlds_makes_no_float_copy_of_the_whole_outcome_matrix() -> None:
    """The real-scale prior's bias (2700 x 20999 outcomes) took a 450 MB float copy and 4 s on a loaded machine."""
    import tracemalloc

    rng = np.random.default_rng(4)
    x = rng.random((2000, 5000)) < 0.6  # a float64 copy would be 80 MB
    weights = rng.integers(1, 4, 2000).astype(np.float64)
    expected = 0.99 * (weights @ x.astype(np.float64)) / weights.sum() + 0.01 * 0.5
    for w in (None, weights):
        tracemalloc.start()
        theta = bias_from_worlds(x, w)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        assert peak < 8 * 1024 * 1024, peak
        want = 0.99 * x.mean(axis=0) + 0.005 if w is None else expected
        np.testing.assert_allclose(theta, want, rtol=0, atol=1e-15)
