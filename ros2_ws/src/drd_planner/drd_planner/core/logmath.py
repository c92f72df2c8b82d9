"""Numerically safe log-space helpers."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from drd_planner.arrays import FloatArray

_LOG_HALF = -0.6931471805599453


def log1mexp(x: npt.ArrayLike) -> FloatArray:
    """log(1 - exp(x)) for x <= 0, elementwise; -inf at x == 0, accurate near 0 and near -inf."""
    xa = np.asarray(x, dtype=np.float64)
    if xa.size and xa.max() <= _LOG_HALF:  # every x takes the second form (the usual case): no masks
        out: FloatArray = np.exp(xa)
        np.negative(out, out=out)
        return np.log1p(out, out=out)
    out = np.full(xa.shape, -np.inf)
    neg = xa < 0
    xn = xa[neg]
    with np.errstate(divide="ignore"):
        out[neg] = np.where(xn > _LOG_HALF, np.log(-np.expm1(xn)), np.log1p(-np.exp(xn)))
    return out


def argmax_first(values: npt.ArrayLike, *, rtol: float = 0.0) -> int:
    """Index of the first maximum; with ``rtol`` > 0 the first value within ``rtol * |max|`` of it.

    A relative tolerance makes ties robust to rounding: two implementations that compute the same
    scores by different sums then still agree on which test comes first.
    """
    v = np.asarray(values, dtype=np.float64)
    best = v.max()
    if rtol == 0.0 or not np.isfinite(best):
        return int(np.argmax(v))
    return int(np.argmax(v >= best - rtol * abs(best)))
