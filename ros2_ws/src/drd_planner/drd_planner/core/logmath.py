"""Numerically safe log-space helpers, on arrays and on single floats.

The scalar forms (:func:`log1mexp_scalar`, :func:`logaddexp_scalar`) take the same branches and make the
same calls as their elementwise ``numpy`` counterparts (:func:`log1mexp`, ``np.logaddexp``), through
:mod:`math`: where ``numpy``'s float64 ``exp``/``log`` family is the C library's, as on machines without
AVX-512 (``tests/core/test_logmath.py`` checks it), they give the same numbers bit for bit.
"""

from __future__ import annotations

import math

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


def log1mexp_scalar(x: float) -> float:
    """:func:`log1mexp` of one float: log(1 - exp(x)) for x <= 0, -inf at x >= 0."""
    if not x < 0.0:
        return -math.inf
    if x > _LOG_HALF:
        return math.log(-math.expm1(x))
    return math.log1p(-math.exp(x))


#: log 2, as ``numpy``'s ``logaddexp`` adds it when both arguments are equal.
_LOG_2 = math.log(2.0)


def logaddexp_scalar(x: float, y: float) -> float:
    """log(exp(x) + exp(y)) of two floats (not NaN), by the steps of ``np.logaddexp``."""
    if x == y:  # equal infinities too
        return x + _LOG_2
    d = x - y
    if d > 0:
        return x + math.log1p(math.exp(-d))
    return y + math.log1p(math.exp(d))


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
