"""Table-1 statistics (docs/algorithms.md, "Evaluation protocol"): relative extra cost over a reference.

Per test world j and policy a the *relative extra cost* is ``(c_a(j) - c_ref(j)) / c_ref(j)`` with the
reference ``direct_bisect`` (the paper's method). Per dataset the paper reports the 40th and 60th
percentiles of this ratio (MATLAB ``prctile``: a distribution-free ~96% interval for the *median*, not
for the mean), after dropping the problems on which a designated subset of algorithms all made the same
number of checks (the authors' tie filter). We report the interval with and without that filter, and the
mean with a seeded percentile-bootstrap confidence interval.

How failures enter: an episode that failed (the policy gave up, or hit the check cap) counts with the
number of checks it actually made (the cap, for capped episodes). Its relative extra cost is therefore an
*optimistic* figure for that policy; the number of failed episodes is reported next to every statistic.
Worlds where the reference made no check (impossible for a solvable world) give NaN and are ignored.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import BoolArray, FloatArray
from drd_planner.exceptions import DrdError

#: The policy every other is compared with (the paper's DiRECt + BiSECt).
REFERENCE = "direct_bisect"
#: The policies whose all-equal costs make a problem "tied" (the authors' ``mvp_idx``): the policies of
#: the paper's table among these names. Only those actually run take part.
TIE_SUBSET = ("direct_bisect", "bisect", "max_tally", "set_cover", "mvoi", "lazysp_set")
#: Percentiles of the Table-1 interval.
LOW_PERCENTILE = 40.0
HIGH_PERCENTILE = 60.0
#: Default bootstrap resamples and confidence level.
DEFAULT_RESAMPLES = 2000
DEFAULT_LEVEL = 0.95


class BenchmarkError(DrdError):
    """A benchmark statistic or report was asked for with inconsistent inputs."""


def matlab_prctile(values: npt.ArrayLike, percent: float | Sequence[float]) -> FloatArray:
    """Percentiles exactly as MATLAB's ``prctile`` computes them (NaN entries are ignored).

    The sorted data x_1 <= ... <= x_n are placed at percent positions ``100 (i - 0.5) / n``; values in
    between are interpolated linearly and values outside ``[50 / n, 100 - 50 / n]`` clamp to x_1 / x_n.
    This is Hyndman & Fan type 5 (numpy's ``method="hazen"``).

    Args:
        values: (n,) sample; NaN entries are dropped first.
        percent: one percentage or a sequence of them, each in [0, 100].

    Returns:
        (k,) float64 percentiles, one per requested percentage; all NaN when no finite value is left.
    """
    p = np.atleast_1d(np.asarray(percent, dtype=np.float64))
    if np.any(~np.isfinite(p)) or np.any(p < 0) or np.any(p > 100):
        raise BenchmarkError(f"percentages must lie in [0, 100], got {p.tolist()}")
    x = np.asarray(values, dtype=np.float64).ravel()
    x = np.sort(x[~np.isnan(x)])
    if x.size == 0:
        return np.full(p.shape, np.nan)
    positions = 100.0 * (np.arange(1, x.size + 1) - 0.5) / x.size
    return np.asarray(np.interp(p, positions, x), dtype=np.float64)


def bootstrap_mean_ci(
    values: npt.ArrayLike,
    *,
    resamples: int = DEFAULT_RESAMPLES,
    level: float = DEFAULT_LEVEL,
    seed: int = 0,
) -> tuple[float, float, float]:
    """Mean and percentile-bootstrap confidence interval of the mean (NaN entries are ignored).

    All ``resamples`` resamples (each n draws with replacement) are drawn at once from
    ``numpy.random.default_rng(seed)``, so the interval is a pure function of the data and the seed.

    Args:
        values: (n,) sample.
        resamples: number of bootstrap resamples (>= 1).
        level: confidence level in (0, 1).
        seed: seed of the resampling.

    Returns:
        ``(mean, low, high)``; all NaN for an empty sample.
    """
    if resamples < 1:
        raise BenchmarkError(f"resamples must be at least 1, got {resamples}")
    if not 0.0 < level < 1.0:
        raise BenchmarkError(f"confidence level must lie in (0, 1), got {level}")
    x = np.asarray(values, dtype=np.float64).ravel()
    x = x[~np.isnan(x)]
    if x.size == 0:
        return float("nan"), float("nan"), float("nan")
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, x.size, size=(resamples, x.size))
    means = x[idx].mean(axis=1)
    tail = 50.0 * (1.0 - level)
    low, high = np.percentile(means, [tail, 100.0 - tail])
    return float(x.mean()), float(low), float(high)


def relative_extra_cost(costs: npt.ArrayLike, reference: npt.ArrayLike) -> FloatArray:
    """Per world ``(c - c_ref) / c_ref``.

    Args:
        costs: (n,) the policy's checks per test world.
        reference: (n,) the reference policy's checks on the same worlds.

    Returns:
        (n,) float64 relative extra cost (0 = as good as the reference, 0.5 = 50% more checks); NaN
        where the reference cost is not positive.
    """
    c = np.asarray(costs, dtype=np.float64).ravel()
    r = np.asarray(reference, dtype=np.float64).ravel()
    if c.shape != r.shape:
        raise BenchmarkError(f"costs ({c.size}) and reference costs ({r.size}) differ in length")
    out = np.full(c.shape, np.nan)
    ok = r > 0
    out[ok] = (c[ok] - r[ok]) / r[ok]
    return out


def present_subset(subset: Sequence[str], available: Sequence[str]) -> tuple[str, ...]:
    """The names of ``subset`` that were run (in ``subset`` order)."""
    have = set(available)
    return tuple(name for name in subset if name in have)


def tie_filter(checks: Mapping[str, npt.ArrayLike], subset: Sequence[str]) -> BoolArray:
    """Which problems survive the authors' tie filter (``any(diff(cost(:, mvp_idx), 1, 2), 2)``).

    A problem is dropped when every policy of ``subset`` made the same number of checks on it. With
    fewer than two subset policies present nothing can be compared and every problem is kept (MATLAB
    would drop everything; we do not follow that degenerate case).

    Args:
        checks: policy name -> (n,) checks per test world.
        subset: the designated policies; names not in ``checks`` are ignored.

    Returns:
        (n,) bool, True for the problems kept.
    """
    used = present_subset(subset, list(checks))
    lengths = {np.asarray(c).size for c in checks.values()}
    if len(lengths) > 1:
        raise BenchmarkError(f"policies were run on different numbers of worlds: {sorted(lengths)}")
    n = lengths.pop() if lengths else 0
    if len(used) < 2:
        return np.ones(n, dtype=bool)
    table = np.stack([np.asarray(checks[name], dtype=np.float64).ravel() for name in used], axis=1)
    return np.asarray(np.any(table != table[:, :1], axis=1), dtype=bool)


@dataclass(frozen=True)
class Summary:
    """Statistics of one sample of relative extra costs (NaN entries ignored).

    Attributes:
        n: number of finite values.
        p40, p60: MATLAB-``prctile`` 40th and 60th percentiles (the Table-1 cell).
        median: 50th percentile.
        mean: sample mean.
        ci_low, ci_high: percentile-bootstrap confidence interval of the mean.
    """

    n: int
    p40: float
    p60: float
    median: float
    mean: float
    ci_low: float
    ci_high: float

    def as_json(self) -> dict[str, Any]:
        """JSON-safe dict (NaN becomes null)."""
        return {
            "n": self.n,
            "p40": _json_float(self.p40),
            "p60": _json_float(self.p60),
            "median": _json_float(self.median),
            "mean": _json_float(self.mean),
            "mean_ci": [_json_float(self.ci_low), _json_float(self.ci_high)],
        }


def summarise(
    values: npt.ArrayLike,
    *,
    resamples: int = DEFAULT_RESAMPLES,
    level: float = DEFAULT_LEVEL,
    seed: int = 0,
) -> Summary:
    """Percentile interval, median, mean and bootstrap CI of ``values`` ((n,) float)."""
    x = np.asarray(values, dtype=np.float64).ravel()
    p40, median, p60 = matlab_prctile(x, [LOW_PERCENTILE, 50.0, HIGH_PERCENTILE])
    mean, low, high = bootstrap_mean_ci(x, resamples=resamples, level=level, seed=seed)
    n = int(np.count_nonzero(~np.isnan(x)))
    return Summary(n, float(p40), float(p60), float(median), mean, low, high)


@dataclass(frozen=True)
class RelativeCost:
    """One policy's relative extra cost over the reference on one dataset.

    Attributes:
        per_world: (n,) float64 relative extra cost per test world (test-id order).
        unfiltered: statistics over every test world.
        filtered: statistics over the worlds the tie filter keeps.
    """

    per_world: FloatArray
    unfiltered: Summary
    filtered: Summary

    def as_json(self) -> dict[str, Any]:
        """JSON-safe dict with ``per_world``, ``unfiltered`` and ``filtered``."""
        return {
            "per_world": [_json_float(v) for v in self.per_world.tolist()],
            "unfiltered": self.unfiltered.as_json(),
            "filtered": self.filtered.as_json(),
        }


@dataclass(frozen=True)
class Table1:
    """Table-1 statistics of one dataset.

    Attributes:
        reference: the reference policy.
        tie_subset: the tie-filter policies that were present (the filter is off with fewer than two).
        kept: (n,) bool, the test worlds the tie filter keeps.
        policies: policy name -> its relative extra cost (the reference included: all zeros).
        oracle: the oracle lower bound's relative "extra" cost (<= 0), when bounds were given.
        resamples, level, seed: the bootstrap settings.
    """

    reference: str
    tie_subset: tuple[str, ...]
    kept: BoolArray
    policies: dict[str, RelativeCost]
    oracle: RelativeCost | None
    resamples: int
    level: float
    seed: int

    @property
    def num_kept(self) -> int:
        """Number of test worlds kept by the tie filter."""
        return int(self.kept.sum())

    def protocol_json(self) -> dict[str, Any]:
        """The settings that produced these numbers."""
        return {
            "reference": self.reference,
            "tie_subset": list(self.tie_subset),
            "tie_filter_applied": len(self.tie_subset) >= 2,
            "num_worlds": int(self.kept.size),
            "num_kept": self.num_kept,
            "percentiles": [LOW_PERCENTILE, HIGH_PERCENTILE],
            "percentile_method": "MATLAB prctile (Hazen: sorted x_i at 100 (i - 0.5) / n, linear)",
            "bootstrap": {"resamples": self.resamples, "level": self.level, "seed": self.seed},
            "failures": "failed episodes count with the checks they made (the cap when capped)",
        }


def table1_stats(
    checks: Mapping[str, npt.ArrayLike],
    *,
    reference: str = REFERENCE,
    tie_subset: Sequence[str] = TIE_SUBSET,
    lower_bound: npt.ArrayLike | None = None,
    resamples: int = DEFAULT_RESAMPLES,
    level: float = DEFAULT_LEVEL,
    seed: int = 0,
) -> Table1:
    """Relative extra cost statistics of every policy over ``reference`` on one dataset.

    Args:
        checks: policy name -> (n,) checks per test world, all in the same world order.
        reference: the policy the others are normalised by; it must be in ``checks``.
        tie_subset: the designated tie-filter policies (see :func:`tie_filter`).
        lower_bound: (n,) oracle lower bound per world (NaN allowed), or None.
        resamples: bootstrap resamples of the mean's confidence interval.
        level: its confidence level.
        seed: the bootstrap seed.

    Raises:
        BenchmarkError: the reference was not run, or the policies' world counts differ.
    """
    if reference not in checks:
        raise BenchmarkError(
            f"reference policy {reference!r} was not run; relative costs need it (ran: {', '.join(checks)})"
        )
    kept = tie_filter(checks, tie_subset)
    ref = np.asarray(checks[reference], dtype=np.float64).ravel()
    opts: dict[str, Any] = {"resamples": resamples, "level": level, "seed": seed}

    def relative(costs: npt.ArrayLike) -> RelativeCost:
        per_world = relative_extra_cost(costs, ref)
        return RelativeCost(per_world, summarise(per_world, **opts), summarise(per_world[kept], **opts))

    policies = {name: relative(c) for name, c in checks.items()}
    oracle = None if lower_bound is None else relative(lower_bound)
    used = present_subset(tie_subset, list(checks))
    return Table1(reference, used, kept, policies, oracle, resamples, level, seed)


def _json_float(value: float) -> float | None:
    return None if not np.isfinite(value) else float(value)
