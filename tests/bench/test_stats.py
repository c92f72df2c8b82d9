"""Table-1 statistics on hand-made numbers: MATLAB percentiles, the tie filter, bootstrap intervals."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from drd_planner.bench.stats import (
    TIE_SUBSET,
    BenchmarkError,
    Summary,
    bootstrap_mean_ci,
    matlab_prctile,
    present_subset,
    relative_extra_cost,
    summarise,
    table1_stats,
    tie_filter,
)
from drd_planner.exceptions import DrdError

# --------------------------------------------------------------------------------------------------
# MATLAB prctile
# --------------------------------------------------------------------------------------------------


def test_prctile_four_values_by_hand() -> None:
    # Sorted 1, 2, 3, 4 sit at 12.5, 37.5, 62.5, 87.5 percent.
    got = matlab_prctile([4, 1, 3, 2], [0, 10, 12.5, 40, 50, 60, 87.5, 95, 100])
    assert got.tolist() == pytest.approx([1, 1, 1, 2.1, 2.5, 2.9, 4, 4, 4])


def test_prctile_five_values_by_hand() -> None:
    # 10..50 sit at 10, 30, 50, 70, 90 percent: P40 halfway between 20 and 30, P60 between 30 and 40.
    got = matlab_prctile([50, 10, 40, 20, 30], [40, 60, 75])
    assert got.tolist() == pytest.approx([25.0, 35.0, 42.5])


def test_prctile_three_values_by_hand() -> None:
    # 0.2, 0.5, 1.0 sit at 16.67, 50, 83.33 percent.
    p40, p60 = matlab_prctile([1.0, 0.2, 0.5], [40, 60])
    assert p40 == pytest.approx(0.2 + 0.7 * 0.3)
    assert p60 == pytest.approx(0.5 + 0.3 * 0.5)


def test_prctile_ignores_nan_and_handles_tiny_samples() -> None:
    assert matlab_prctile([1, np.nan, 2, 3, 4], 40)[0] == pytest.approx(2.1)
    assert matlab_prctile([7.0], [0, 40, 100]).tolist() == [7.0, 7.0, 7.0]
    assert np.isnan(matlab_prctile([], 40)).all()
    assert np.isnan(matlab_prctile([np.nan, np.nan], [40, 60])).all()
    assert matlab_prctile([1, 2], 40).shape == (1,)


def test_prctile_equals_hazen_definition_on_random_data() -> None:
    rng = np.random.default_rng(3)
    for n in (2, 5, 17, 100):
        x = rng.normal(size=n)
        p = np.linspace(0, 100, 41)
        assert np.allclose(matlab_prctile(x, p), np.percentile(x, p, method="hazen"))
        assert not np.allclose(matlab_prctile(x, [40]), np.percentile(x, [40])) or n == 2


@pytest.mark.parametrize("bad", [-1.0, 100.5, float("nan")])
def test_prctile_rejects_bad_percentages(bad: float) -> None:
    with pytest.raises(BenchmarkError, match="percentages"):
        matlab_prctile([1, 2, 3], bad)


def test_benchmark_error_is_a_drd_error() -> None:
    assert issubclass(BenchmarkError, DrdError)


# --------------------------------------------------------------------------------------------------
# Relative extra cost and the tie filter
# --------------------------------------------------------------------------------------------------


def test_relative_extra_cost() -> None:
    got = relative_extra_cost([10, 15, 8, 3], [10, 10, 4, 0])
    assert got[:3].tolist() == pytest.approx([0.0, 0.5, 1.0])
    assert math.isnan(got[3])
    assert relative_extra_cost([5], [10])[0] == pytest.approx(-0.5)
    with pytest.raises(BenchmarkError, match="differ in length"):
        relative_extra_cost([1, 2], [1])


def test_tie_filter_drops_exactly_the_tied_problems() -> None:
    checks = {
        "direct_bisect": [5, 6, 7, 8, 9],
        "bisect": [5, 7, 7, 9, 9],
        "mvoi": [5, 6, 7, 8, 10],
        "random": [1, 2, 3, 4, 5],  # not in the subset: its differences never keep a problem
    }
    kept = tie_filter(checks, TIE_SUBSET)
    assert kept.tolist() == [False, True, False, True, True]
    assert present_subset(TIE_SUBSET, list(checks)) == ("direct_bisect", "bisect", "mvoi")
    # The subset is a parameter: on {direct_bisect, mvoi} only problem 4 differs.
    assert tie_filter(checks, ["direct_bisect", "mvoi"]).tolist() == [False, False, False, False, True]


def test_tie_filter_needs_two_present_policies() -> None:
    checks = {"direct_bisect": [3, 3], "random": [3, 4]}
    assert tie_filter(checks, TIE_SUBSET).tolist() == [True, True]
    assert tie_filter({}, TIE_SUBSET).size == 0


def test_tie_filter_rejects_ragged_runs() -> None:
    with pytest.raises(BenchmarkError, match="different numbers of worlds"):
        tie_filter({"direct_bisect": [1, 2], "bisect": [1]}, TIE_SUBSET)


# --------------------------------------------------------------------------------------------------
# Bootstrap
# --------------------------------------------------------------------------------------------------


def test_bootstrap_is_deterministic_for_a_seed_and_contains_the_mean() -> None:
    x = [0.0, 0.1, 0.1, 0.3, 0.5, 0.2, 0.9, -0.2, 0.4, 0.0]
    a = bootstrap_mean_ci(x, seed=11)
    b = bootstrap_mean_ci(x, seed=11)
    c = bootstrap_mean_ci(x, seed=12)
    assert a == b
    assert a != c
    mean, low, high = a
    assert mean == pytest.approx(np.mean(x))
    assert low < mean < high
    assert min(x) <= low
    assert high <= max(x)


def test_bootstrap_width_matches_the_normal_theory() -> None:
    x = np.random.default_rng(0).normal(loc=2.0, scale=1.0, size=400)
    mean, low, high = bootstrap_mean_ci(x, resamples=4000, seed=1)
    half = 1.96 * x.std(ddof=1) / math.sqrt(x.size)
    assert (high - low) / 2 == pytest.approx(half, rel=0.15)
    assert (low + high) / 2 == pytest.approx(mean, abs=0.02)


def test_bootstrap_level_and_degenerate_samples() -> None:
    x = np.arange(30, dtype=float)
    _, lo90, hi90 = bootstrap_mean_ci(x, level=0.90, seed=0)
    _, lo99, hi99 = bootstrap_mean_ci(x, level=0.99, seed=0)
    assert lo99 < lo90
    assert hi90 < hi99
    assert bootstrap_mean_ci([2.5, 2.5, 2.5], seed=0) == (2.5, 2.5, 2.5)
    assert all(math.isnan(v) for v in bootstrap_mean_ci([np.nan]))
    assert bootstrap_mean_ci([1.0, np.nan, 3.0], seed=0)[0] == pytest.approx(2.0)


@pytest.mark.parametrize(("kwargs", "match"), [({"resamples": 0}, "resamples"), ({"level": 1.0}, "level")])
def test_bootstrap_rejects_bad_settings(kwargs: dict[str, float], match: str) -> None:
    with pytest.raises(BenchmarkError, match=match):
        bootstrap_mean_ci([1.0, 2.0], **kwargs)  # type: ignore[arg-type]


# --------------------------------------------------------------------------------------------------
# table1_stats
# --------------------------------------------------------------------------------------------------


def test_table1_stats_by_hand() -> None:
    checks = {
        "direct_bisect": [10, 10, 10, 10, 10],
        "bisect": [10, 12, 15, 20, 10],
        "random": [20, 10, 10, 10, 5],
    }
    table = table1_stats(checks, lower_bound=[5, 5, 10, 5, np.nan], resamples=500, seed=4)
    assert table.reference == "direct_bisect"
    assert table.tie_subset == ("direct_bisect", "bisect")
    assert table.kept.tolist() == [False, True, True, True, False]
    assert table.num_kept == 3
    bis = table.policies["bisect"]
    assert bis.per_world.tolist() == pytest.approx([0, 0.2, 0.5, 1.0, 0])
    # Filtered: 0.2, 0.5, 1.0 (see test_prctile_three_values_by_hand).
    assert bis.filtered.n == 3
    assert bis.filtered.p40 == pytest.approx(0.41)
    assert bis.filtered.p60 == pytest.approx(0.65)
    assert bis.filtered.median == pytest.approx(0.5)
    assert bis.filtered.mean == pytest.approx(1.7 / 3)
    # Unfiltered: 0, 0, 0.2, 0.5, 1.0 at 10, 30, 50, 70, 90 percent.
    assert bis.unfiltered.n == 5
    assert bis.unfiltered.p40 == pytest.approx(0.1)
    assert bis.unfiltered.p60 == pytest.approx(0.35)
    assert bis.unfiltered.mean == pytest.approx(0.34)
    assert bis.unfiltered.ci_low <= 0.34 <= bis.unfiltered.ci_high
    ref = table.policies["direct_bisect"]
    assert ref.unfiltered.p40 == ref.unfiltered.p60 == ref.unfiltered.mean == 0.0
    rnd = table.policies["random"]
    assert rnd.per_world.tolist() == pytest.approx([1.0, 0, 0, 0, -0.5])
    assert rnd.filtered.n == 3
    assert rnd.filtered.p60 == 0.0
    assert table.oracle is not None
    assert table.oracle.per_world[:4].tolist() == pytest.approx([-0.5, -0.5, 0.0, -0.5])
    assert table.oracle.unfiltered.n == 4  # the NaN bound is ignored
    protocol = table.protocol_json()
    assert protocol["num_kept"] == 3
    assert protocol["tie_filter_applied"] is True
    assert protocol["bootstrap"] == {"resamples": 500, "level": 0.95, "seed": 4}
    json.dumps(protocol, allow_nan=False)


def test_table1_stats_is_deterministic_and_json_safe() -> None:
    checks = {"direct_bisect": [3, 4, 5, 6], "bisect": [3, 4, 5, 6]}  # every problem tied
    a = table1_stats(checks, seed=2)
    b = table1_stats(checks, seed=2)
    assert a.policies["bisect"].as_json() == b.policies["bisect"].as_json()
    assert a.num_kept == 0
    doc = a.policies["bisect"].as_json()
    assert doc["filtered"] == {
        "n": 0,
        "p40": None,
        "p60": None,
        "median": None,
        "mean": None,
        "mean_ci": [None, None],
    }
    assert doc["unfiltered"]["p40"] == 0.0
    json.dumps(doc, allow_nan=False)


def test_table1_stats_needs_the_reference() -> None:
    with pytest.raises(BenchmarkError, match="direct_bisect"):
        table1_stats({"bisect": [1, 2]})
    table = table1_stats({"bisect": [4, 8], "lazysp": [8, 8]}, reference="bisect", tie_subset=["bisect", "lazysp"])
    assert table.policies["lazysp"].per_world.tolist() == [1.0, 0.0]
    assert table.kept.tolist() == [True, False]


def test_summarise_matches_its_parts() -> None:
    x = np.array([0.3, -0.1, 0.8, 0.0, 0.25, 0.6])
    s = summarise(x, resamples=300, seed=9)
    assert isinstance(s, Summary)
    assert (s.p40, s.p60) == tuple(matlab_prctile(x, [40, 60]).tolist())
    assert (s.mean, s.ci_low, s.ci_high) == bootstrap_mean_ci(x, resamples=300, seed=9)
    assert s.n == 6
