"""The log-space helpers: the scalar forms take numpy's steps, so they equal the elementwise forms."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import libm_numpy

from drd_planner.core.logmath import log1mexp, log1mexp_scalar, logaddexp_scalar


def _values(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x = -rng.exponential(2.0, 500)
    x[:5] = [0.0, -1e-300, -0.6931471805599453, -0.69314718055994, -745.2]  # the edges of both branches
    return x


@pytest.mark.parametrize("seed", range(3))
def test_log1mexp_scalar_equals_the_elementwise_form(seed: int) -> None:
    x = _values(seed)
    vector = log1mexp(x)
    scalar = np.array([log1mexp_scalar(v) for v in x.tolist()])
    assert vector[0] == scalar[0] == -np.inf
    assert np.isfinite(scalar[1:]).all()
    if libm_numpy():
        assert scalar.tolist() == vector.tolist()  # bit for bit
    else:  # numpy's own vector forms: the same up to their last bits
        np.testing.assert_allclose(scalar[1:], vector[1:], rtol=1e-13)
    # and both are log(1 - e^x)
    mid = x[(x < -1e-3) & (x > -30)]
    np.testing.assert_allclose(log1mexp(mid), np.log(1.0 - np.exp(mid)), rtol=1e-9)


@pytest.mark.parametrize("seed", range(3))
def test_logaddexp_scalar_equals_numpy(seed: int) -> None:
    rng = np.random.default_rng(10 + seed)
    x, y = rng.normal(0.0, 5.0, 500), rng.normal(0.0, 5.0, 500)
    x[::37], y[::41] = -np.inf, -np.inf
    y[::53] = x[::53]  # equal arguments (both -inf at 0)
    vector = np.logaddexp(x, y)
    scalar = np.array([logaddexp_scalar(a, b) for a, b in zip(x.tolist(), y.tolist(), strict=True)])
    assert scalar[0] == -np.inf
    if libm_numpy():
        assert scalar.tolist() == vector.tolist()
    else:
        np.testing.assert_allclose(scalar, vector, rtol=1e-13)
